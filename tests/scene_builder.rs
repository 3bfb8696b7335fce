//! Scenes built in code (`SceneBuilder`): the same validated scene as the JSON loader gives for
//! the same definitions (bit-identical images), and the same errors naming object and field.

mod common;
use common::*;
use illum::scene::SceneBuilder;
use illum::scene::format::*;

/// A 4x2 linear RGBA map for the dome.
fn sky_pixels() -> Vec<f32> {
    (0..8)
        .flat_map(|i| {
            let v = 0.1 + 0.1 * i as f32;
            [v, 0.5 * v, 0.25 + 0.05 * i as f32, 1.0]
        })
        .collect()
}

const POSITIONS: [[f32; 3]; 4] = [
    [-1.0, 0.0, -1.0],
    [1.0, 0.0, -1.0],
    [1.0, 0.0, 1.0],
    [-1.0, 0.0, 1.0],
];
const INDICES: [u32; 6] = [0, 2, 1, 0, 3, 2];

/// The scene of `json(…)`, in code.
fn built(ball_diffuse: [f64; 3]) -> SceneBuilder {
    let mut b = SceneBuilder::new(CameraDef::look_at(
        [0.0, 1.2, 3.0],
        [0.0, 0.3, 0.0],
        40.0,
        [13, 9],
    ));
    b.texture_pixels("sky", 4, 2, &sky_pixels(), false)
        .material(
            "floor",
            MaterialDef {
                diffuse: [0.6, 0.6, 0.6],
                specular: vec![LobeDef {
                    model: ModelDef::Ggx,
                    roughness: NumOrArray::One(0.2),
                    fresnel: default_fresnel(),
                }],
                ..Default::default()
            },
        )
        .material(
            "ball",
            MaterialDef {
                diffuse: ball_diffuse,
                ..Default::default()
            },
        )
        .mesh(
            "floor",
            "floor",
            &POSITIONS,
            &INDICES,
            Some(TransformDef {
                scale: Some(NumOrArray::One(3.0)),
                ..Default::default()
            }),
        )
        .shape("ball", ShapeDef::sphere([0.0, 0.5, 0.0], 0.5, "ball"))
        .light(
            "key",
            LightDef::rect([1.0, 2.0, 1.0], [-0.4, -1.0, -0.4], [0.8, 0.8], 6.0),
        )
        .light(
            "sky",
            LightDef {
                texture: Some("sky".into()),
                ..LightDef::dome([0.5, 0.5, 0.5])
            },
        );
    b
}

fn json(exr: &str) -> String {
    format!(
        r#"{{"camera": {{"position": [0, 1.2, 3], "look_at": [0, 0.3, 0], "fov_y": 40, "resolution": [13, 9]}},
    "textures": {{"sky": {{"file": "{exr}"}}}},
    "materials": {{"floor": {{"diffuse": [0.6, 0.6, 0.6], "specular": [{{"model": "ggx", "roughness": 0.2}}]}},
                  "ball": {{"diffuse": [0.7, 0.3, 0.2]}}}},
    "shapes": {{"floor": {{"mesh": {{"positions": [[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]], "indices": [0, 2, 1, 0, 3, 2]}},
                          "material": "floor", "transform": {{"scale": 3}}}},
               "ball": {{"sphere": {{"center": [0, 0.5, 0], "radius": 0.5}}, "material": "ball"}}}},
    "lights": {{"key": {{"rect": {{"center": [1, 2, 1], "normal": [-0.4, -1, -0.4], "size": [0.8, 0.8]}}, "intensity": 6}},
               "sky": {{"dome": {{}}, "color": [0.5, 0.5, 0.5], "texture": "sky"}}}}}}"#
    )
}

#[test]
fn a_built_scene_renders_bit_identical_to_the_loaded_file() {
    let px = sky_pixels();
    let exr = temp_path("builder-sky.exr");
    exr::prelude::write_rgba_file(&exr, 4, 2, |x, y| {
        let i = (y * 4 + x) * 4;
        (px[i], px[i + 1], px[i + 2], px[i + 3])
    })
    .unwrap();
    let file = temp_path("builder.json");
    std::fs::write(&file, json("builder-sky.exr")).unwrap();
    let loaded = illum::scene::load(&file).unwrap();
    let scene = built([0.7, 0.3, 0.2]).build().unwrap();
    assert_eq!(scene.textures[0].texels, loaded.textures[0].texels);
    let ctx = context();
    let a = render_with(&ctx, &loaded, 8, 3);
    let b = render_with(&ctx, &scene, 8, 3);
    assert_eq!(a.film, b.film, "builder and loader give other images");
    // The comparison can fail: one value changed in code changes the image.
    let other = render_with(&ctx, &built([0.7, 0.3, 0.21]).build().unwrap(), 8, 3);
    assert_ne!(a.film.beauty, other.film.beauty);
    assert_no_validation_messages(&ctx);
}

/// The same mistakes in code and in a file give the same messages (the builder's origin in
/// place of the file name).
#[test]
fn builder_errors_are_the_loaders() {
    let file_error = |json: &str| {
        illum::scene::from_json_str(json, "app", std::path::Path::new("."))
            .unwrap_err()
            .to_string()
    };
    let code_error = |b: &mut SceneBuilder| b.origin("app").build().unwrap_err().to_string();
    let base = r#""camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_y": 40, "resolution": [4, 4]}"#;
    let mut b = built([1.5, 0.3, 0.2]);
    let e = code_error(&mut b);
    assert_eq!(
        e,
        file_error(&format!(
            r#"{{{base}, "materials": {{"ball": {{"diffuse": [1.5, 0.3, 0.2]}}}},
                "shapes": {{"ball": {{"sphere": {{"center": [0, 0.5, 0], "radius": 0.5}}, "material": "ball"}}}}}}"#
        ))
    );
    assert!(
        e.contains("materials.ball.diffuse") && e.contains("1.5"),
        "{e}"
    );
    let mut b = built([0.5; 3]);
    b.shape("moon", ShapeDef::sphere([0.0; 3], -1.0, "cheese"));
    let e = code_error(&mut b);
    assert_eq!(
        e,
        file_error(&format!(
            r#"{{{base}, "materials": {{"floor": {{}}, "ball": {{}}}},
                "shapes": {{"moon": {{"sphere": {{"center": [0, 0, 0], "radius": -1}}, "material": "cheese"}}}}}}"#
        ))
    );
    assert!(
        e.contains("shapes.moon.material") && e.contains("\"floor\""),
        "{e}"
    );
    let mut b = built([0.5; 3]);
    b.shape("ball", ShapeDef::sphere([0.0; 3], 1.0, "ball"));
    let e = code_error(&mut b);
    assert!(
        e.contains("shapes.ball") && e.contains("duplicate name"),
        "{e}"
    );
    let mut b = built([0.5; 3]);
    b.texture_pixels("bad", 2, 2, &[0.5; 15], false);
    let e = code_error(&mut b);
    assert!(
        e.contains("textures.bad.pixels") && e.contains("15 values for 2x2"),
        "{e}"
    );
    let mut b = built([0.5; 3]);
    let mut px = [0.5f32; 16];
    px[13] = f32::NAN;
    b.texture_pixels("nan", 2, 2, &px, false);
    let e = code_error(&mut b);
    assert!(
        e.contains("textures.nan.pixels") && e.contains("pixel (1, 1)"),
        "{e}"
    );
    let mut b = built([0.5; 3]);
    b.mesh("tri", "ball", &POSITIONS[..3], &[0, 1, 7], None);
    let e = code_error(&mut b);
    assert!(
        e.contains("shapes.tri.mesh.indices[2]") && e.contains("out of range"),
        "{e}"
    );
}
