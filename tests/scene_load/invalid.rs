//! Each kind of bad input gives its own message naming the file, the field path and the value.

use super::{CAMERA, assert_error, error_of_file, load_in, temp_dir};
use std::path::Path;

const GREY: &str = r#""materials": { "grey": {} }"#;

/// A file with the standard camera, a "grey" material and the given shapes.
fn with_shapes(shapes: &str) -> String {
    format!("{{ {CAMERA}, {GREY}, \"shapes\": {{ {shapes} }} }}")
}

/// A file with the standard camera, a "grey" material, a ball, and the given lights.
fn with_lights(lights: &str) -> String {
    with_shapes(&format!(
        r#""ball": {{ "sphere": {{ "center": [0, 1, 0], "radius": 1 }}, "material": "grey" }} }},
           "lights": {{ {lights} "#
    ))
}

/// A file with one sphere using material "m", defined as given.
fn with_material(material: &str) -> String {
    format!(
        r#"{{ {CAMERA}, "materials": {{ "m": {material} }},
             "shapes": {{ "ball": {{ "sphere": {{ "center": [0, 1, 0], "radius": 1 }}, "material": "m" }} }} }}"#
    )
}

fn with_camera(camera: &str) -> String {
    format!(
        r#"{{ "camera": {camera}, {GREY},
             "shapes": {{ "ball": {{ "sphere": {{ "center": [0, 1, 0], "radius": 1 }}, "material": "grey" }} }} }}"#
    )
}

#[test]
fn negative_radius_names_file_field_and_value() {
    let text = with_shapes(
        r#""ball": { "sphere": { "center": [0, 1, 0], "radius": -1 }, "material": "grey" }"#,
    );
    assert_eq!(
        error_of_file(&text),
        "bad.json: shapes.ball.sphere.radius: must be a positive finite number, got -1"
    );
}

#[test]
fn unknown_field_has_line_column_and_path() {
    let text = format!(
        "{{\n  {CAMERA},\n  {GREY},\n  \"shapes\": {{\n    \"ball\": {{ \"sphere\": {{ \"center\": [0, 1, 0], \"raduis\": 1 }}, \"material\": \"grey\" }}\n  }}\n}}"
    );
    assert_eq!(
        error_of_file(&text),
        "bad.json: line 5 column 55: shapes.ball.sphere.raduis: \
         unknown field \"raduis\", expected \"center\" or \"radius\""
    );
}

#[test]
fn non_finite_literals_are_parse_errors_with_position() {
    let nan = with_shapes(
        r#""ball": { "sphere": { "center": [0, 1, 0], "radius": NaN }, "material": "grey" }"#,
    );
    assert_error(
        &nan,
        &[
            "bad.json: line 1 column ",
            "shapes.ball.sphere.radius",
            "expected value",
        ],
    );
    let huge = with_shapes(
        r#""ball": { "sphere": { "center": [0, 1e999, 0], "radius": 1 }, "material": "grey" }"#,
    );
    assert_error(
        &huge,
        &[
            "bad.json: line 1 column ",
            "shapes.ball.sphere.center",
            "number out of range",
        ],
    );
}

#[test]
fn bad_values_give_specific_errors() {
    let cases: Vec<(String, &[&str])> = vec![
        (
            with_shapes(
                r#""floor": { "rect": { "center": [0, 0, 0], "normal": [0, 0, 0], "size": [1, 1] }, "material": "grey" }"#,
            ),
            &[
                "bad.json: shapes.floor.rect.normal: must be a non-zero finite vector, got [0, 0, 0]",
            ],
        ),
        (
            with_shapes(
                r#""floor": { "rect": { "center": [0, 0, 0], "normal": [0, 1, 0], "size": [1, 1], "up": [0, 2, 0] }, "material": "grey" }"#,
            ),
            &[
                "bad.json: shapes.floor.rect.up: must not be parallel to the normal [0, 1, 0], got [0, 2, 0]",
            ],
        ),
        (
            with_shapes(
                r#""floor": { "rect": { "center": [0, 0, 0], "normal": [0, 1, 0], "size": [1, 0] }, "material": "grey" }"#,
            ),
            &["bad.json: shapes.floor.rect.size[1]: must be a positive finite number, got 0"],
        ),
        (
            with_shapes(
                r#""coin": { "disk": { "center": [0, 0, 0], "normal": [0, 1, 0], "radius": 0 }, "material": "grey" }"#,
            ),
            &["bad.json: shapes.coin.disk.radius: must be a positive finite number, got 0"],
        ),
        (
            with_shapes(
                r#""tri": { "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "tangents": [[1, 0, 0, 1], [1, 0, 0, 1], [1, 0, 0, 0.5]] }, "material": "grey" }"#,
            ),
            &[
                "bad.json: shapes.tri.mesh.tangents[2]: w (the handedness) must be 1 or -1, got [1, 0, 0, 0.5]",
            ],
        ),
        (
            // Lights may have zero size (they emit nothing), but not a negative one.
            with_lights(r#""bulb": { "sphere": { "center": [0, 3, 0], "radius": -0.5 } }"#),
            &["bad.json: lights.bulb.sphere.radius: must be a finite number >= 0, got -0.5"],
        ),
        (
            with_camera(r#"{ "position": [0, 1, 5], "look_at": [0, 0, 0], "fov_y": 180 }"#),
            &["bad.json: camera.fov_y: must be in (0, 180) degrees, got 180"],
        ),
        (
            with_camera(r#"{ "position": [0, 1, 5], "look_at": [0, 0, 0], "fov_y": 0 }"#),
            &["bad.json: camera.fov_y: must be in (0, 180) degrees, got 0"],
        ),
        (
            with_camera(
                r#"{ "position": [0, 1, 5], "look_at": [0, 0, 0], "fov_y": 40, "resolution": [0, 512] }"#,
            ),
            &["bad.json: camera.resolution: width and height must be > 0, got [0, 512]"],
        ),
        (
            with_camera(
                r#"{ "position": [0, 1, 5], "look_at": [0, 0, 0], "fov_y": 40, "resolution": [-1, 512] }"#,
            ),
            &[
                "bad.json: line 1 column ",
                "camera.resolution[0]: invalid value: integer \"-1\", expected u32",
            ],
        ),
        (
            with_camera(r#"{ "position": [0, 1, 5], "look_at": [0, 1, 5], "fov_y": 40 }"#),
            &[
                "bad.json: camera.look_at: must differ from camera.position [0, 1, 5], got [0, 1, 5]",
            ],
        ),
        (
            with_camera(r#"{ "position": [0, 5, 0], "look_at": [0, 0, 0], "fov_y": 40 }"#),
            &[
                "bad.json: camera.up: must not be parallel to the view direction (set camera.up), got [0, 1, 0]",
            ],
        ),
        (
            with_camera(r#"{ "position": [0, 5, 0], "look_at": [0, 0, 0] }"#),
            &["bad.json: camera.fov_y: missing (required unless camera.gltf is given)"],
        ),
        (
            with_camera(r#"{ "gltf": "ball" }"#),
            &["bad.json: camera.gltf: must name a shape with a gltf geometry, got \"ball\""],
        ),
        (
            with_shapes(
                r#""ball": { "sphere": { "center": [0, 1, 0], "radius": 1 }, "material": "gray" }"#,
            ),
            &["bad.json: shapes.ball.material: no such material (known: \"grey\"), got \"gray\""],
        ),
        (
            with_shapes(r#""ball": { "sphere": { "center": [0, 1, 0], "radius": 1 } }"#),
            &["bad.json: shapes.ball.material: missing: sphere shapes need a material"],
        ),
        (
            with_material(r#"{ "diffuse_texture": "wood" }"#),
            &[
                "bad.json: materials.m.diffuse_texture: no such texture (none are defined), got \"wood\"",
            ],
        ),
        (
            with_lights(
                r#""key": { "sphere": { "center": [0, 3, 0], "radius": 1 }, "texture": "hdri" }"#,
            ),
            &["bad.json: lights.key.texture: no such texture (none are defined), got \"hdri\""],
        ),
        (
            with_shapes(
                r#""t": { "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "indices": [0, 1, 3] }, "material": "grey" }"#,
            ),
            &[
                "bad.json: shapes.t.mesh.indices[2]: index out of range (the mesh has 3 positions), got 3",
            ],
        ),
        (
            with_shapes(
                r#""t": { "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "indices": [0, 1, 2, 0] }, "material": "grey" }"#,
            ),
            &[
                "bad.json: shapes.t.mesh.indices: the number of indices must be a non-zero multiple of 3, got 4 indices",
            ],
        ),
        (
            with_shapes(
                r#""t": { "mesh": { "positions": [[0, 0, 0], [1, 0, 0]] }, "material": "grey" }"#,
            ),
            &[
                "bad.json: shapes.t.mesh.positions: without \"indices\", the number of positions must be a multiple of 3, got 2 positions",
            ],
        ),
        (
            with_shapes(
                r#""t": { "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "normals": [[0, 0, 1], [0, 0, 1]] }, "material": "grey" }"#,
            ),
            &[
                "bad.json: shapes.t.mesh.normals: must have one entry per position (3), got 2 entries",
            ],
        ),
        (
            with_shapes(
                r#""t": { "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]] }, "material": "grey", "transform": { "scale": [1, 0, 1] } }"#,
            ),
            &[
                "bad.json: shapes.t.transform: must be invertible (no zero scale or collapsed axes), got determinant 0",
            ],
        ),
        (
            with_shapes(
                r#""t": { "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]] }, "material": "grey",
                  "transform": { "translate": [1, 0, 0], "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1] } }"#,
            ),
            &[
                "bad.json: shapes.t.transform.matrix: give either \"matrix\" or \"translate\"/\"rotate\"/\"scale\", not both",
            ],
        ),
        (
            with_shapes(
                r#""t": { "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]] }, "material": "grey",
                  "transform": { "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1] } }"#,
            ),
            &[
                "bad.json: shapes.t.transform.matrix: must be affine: last row [0, 0, 0, 1], got [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1]",
            ],
        ),
        (
            with_shapes(
                r#""ball": { "sphere": { "center": [0, 1, 0], "radius": 1 }, "material": "grey", "transform": { "scale": 2 } }"#,
            ),
            &["bad.json: shapes.ball.transform: sphere shapes take no transform"],
        ),
        (
            with_shapes(
                r#""x": { "sphere": { "center": [0, 1, 0], "radius": 1 }, "disk": { "center": [0, 0, 0], "normal": [0, 1, 0], "radius": 1 }, "material": "grey" }"#,
            ),
            &[
                "bad.json: shapes.x: must have exactly one of \"sphere\", \"rect\", \"disk\", \"mesh\", \"gltf\", \"instance\", got \"sphere\", \"disk\"",
            ],
        ),
        (
            with_shapes(r#""x": { "instance": "ball" }"#),
            &["bad.json: shapes.x.instance: must name an earlier shape with a mesh, got \"ball\""],
        ),
        (
            with_shapes(
                r#""m": { "mesh": { "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]] }, "material": "grey" }, "x": { "instance": "m", "material": "grey" }"#,
            ),
            &[
                "bad.json: shapes.x.material: an instance takes the material of the shape it places again",
            ],
        ),
        (
            with_shapes(r#""x": { "material": "grey" }"#),
            &["bad.json: shapes.x: must have exactly one of", "got none"],
        ),
        (
            with_material(r#"{ "specular": [{ "model": "dbrdf", "roughness": -0.1 }] }"#),
            &[
                "bad.json: materials.m.specular[0].roughness: roughness must be in [0, 1] (0: a perfect mirror), got -0.1",
            ],
        ),
        (
            with_material(r#"{ "specular": [{ "model": "ggx", "roughness": [0.5, 1.5] }] }"#),
            &[
                "bad.json: materials.m.specular[0].roughness[1]: roughness must be in [0, 1] (0: a perfect mirror), got 1.5",
            ],
        ),
        (
            with_material(r#"{ "specular": [{ "model": "ggx", "roughness": [0.5, 0.5, 0.5] }] }"#),
            &[
                "bad.json: line 1 column ",
                "materials.m.specular[0].roughness: invalid length 3, expected a number or an array of 2 numbers",
            ],
        ),
        (
            with_material(
                r#"{ "metallic_roughness": {}, "specular": [{ "model": "ggx", "roughness": 0.5 }] }"#,
            ),
            &[
                "bad.json: materials.m.specular: a metallic_roughness material derives its one lobe: leave specular out, got 1 lobes",
            ],
        ),
        (
            with_material(r#"{ "metallic_roughness": { "metallic": 1.5 } }"#),
            &["bad.json: materials.m.metallic_roughness.metallic: must be in [0, 1], got 1.5"],
        ),
        (
            with_material(r#"{ "metallic_roughness": { "ior": 0.5 } }"#),
            &[
                "bad.json: materials.m.metallic_roughness.ior: must be a finite number >= 1, got 0.5",
            ],
        ),
        (
            with_material(
                r#"{ "metallic_roughness": { "roughness_texture": { "texture": "rough" } } }"#,
            ),
            &[
                "bad.json: materials.m.metallic_roughness.roughness_texture.texture: no such texture",
            ],
        ),
        (
            with_material(
                r#"{ "metallic_roughness": { "metallic_texture": { "texture": "t", "channel": "x" } } }"#,
            ),
            &["materials.m.metallic_roughness.metallic_texture.channel: unknown variant \"x\""],
        ),
        (
            with_material(r#"{ "specular": [{ "model": "phong", "roughness": 0.5 }] }"#),
            &[
                "materials.m.specular[0].model: unknown variant \"phong\", expected one of \"dbrdf\", \"beckmann\", \"ggx\"",
            ],
        ),
        (
            with_material(r#"{ "diffuse": [1.2, 0.5, 0.5] }"#),
            &[
                "bad.json: materials.m.diffuse: each component must be in [0, 1], got [1.2, 0.5, 0.5]",
            ],
        ),
        (
            with_material(r#"{ "emission": [1, -1, 0] }"#),
            &[
                "bad.json: materials.m.emission: each component must be a finite number >= 0, got [1, -1, 0]",
            ],
        ),
        (
            with_material(
                r#"{ "specular": [{ "model": "beckmann", "roughness": 0.5, "fresnel": { "conductor": { "eta": [0, 1, 1], "k": [1, 1, 1] } } }] }"#,
            ),
            &[
                "bad.json: materials.m.specular[0].fresnel.conductor.eta: each component must be a finite number > 0, got [0, 1, 1]",
            ],
        ),
        (
            with_material(
                r#"{ "specular": [{ "model": "ggx", "roughness": 0.5, "fresnel": { "schlick": [0.04, 0.04, 2] } }] }"#,
            ),
            &[
                "bad.json: materials.m.specular[0].fresnel.schlick: each component must be in [0, 1], got [0.04, 0.04, 2]",
            ],
        ),
        (
            with_material(
                r#"{ "specular": [{ "model": "ggx", "roughness": 0.5 }, { "model": "ggx", "roughness": 0.5 }, { "model": "ggx", "roughness": 0.5 }] }"#,
            ),
            &["bad.json: materials.m.specular: at most 2 specular lobes are allowed, got 3 lobes"],
        ),
        (
            with_material(r#"{ "tangent": [0, 0, 0] }"#),
            &["bad.json: materials.m.tangent: must be a non-zero finite vector, got [0, 0, 0]"],
        ),
        (
            with_lights(
                r#""s1": { "sun": { "direction": [0, 1, 0] } }, "s2": { "sun": { "direction": [1, 1, 0] } }"#,
            ),
            &[
                "bad.json: lights.s2.sun: a scene has at most one sun light, and \"s1\" is one already",
            ],
        ),
        (
            with_lights(r#""d1": { "dome": {} }, "d2": { "dome": { "rotation": 10 } }"#),
            &[
                "bad.json: lights.d2.dome: a scene has at most one dome light, and \"d1\" is one already",
            ],
        ),
        (
            with_lights(r#""env": { "dome": {}, "two_sided": true }"#),
            &["bad.json: lights.env.two_sided: a dome light cannot be two-sided, got true"],
        ),
        (
            with_lights(r#""sun": { "sun": { "direction": [0, 1, 0] }, "two_sided": true }"#),
            &["bad.json: lights.sun.two_sided: a sun light cannot be two-sided, got true"],
        ),
        (
            with_lights(r#""sun": { "sun": { "direction": [0, 1, 0], "angular_diameter": 200 } }"#),
            &["bad.json: lights.sun.sun.angular_diameter: must be in [0, 180) degrees, got 200"],
        ),
        (
            with_lights(r#""sun": { "sun": { "direction": [0, 0, 0] } }"#),
            &[
                "bad.json: lights.sun.sun.direction: must be a non-zero finite vector, got [0, 0, 0]",
            ],
        ),
        (
            with_lights(
                r#""key": { "disk": { "center": [0, 3, 0], "normal": [0, -1, 0], "radius": 1 }, "intensity": -1 }"#,
            ),
            &["bad.json: lights.key.intensity: must be a finite number >= 0, got -1"],
        ),
        (
            with_lights(
                r#""key": { "disk": { "center": [0, 3, 0], "normal": [0, -1, 0], "radius": 1 }, "color": [1e300, 0, 0] }"#,
            ),
            &[
                "bad.json: lights.key.color: each component must be a finite number >= 0, got [1e300, 0, 0]",
            ],
        ),
        (
            with_lights(
                r#""key": { "disk": { "center": [0, 3, 0], "normal": [0, -1, 0], "radius": 1 }, "intensity": 1e30, "exposure": 100 }"#,
            ),
            &["bad.json: lights.key: color · intensity · 2^exposure overflows 32-bit floats"],
        ),
        (
            with_lights(
                r#""key": { "disk": { "center": [0, 3, 0], "normal": [0, -1, 0], "radius": 1 }, "colour": [1, 1, 1] }"#,
            ),
            &[
                "bad.json: line 2 column ",
                "lights.key.colour: unknown field \"colour\"",
            ],
        ),
        (
            format!("{{ {CAMERA} }}"),
            &["bad.json: shapes: a scene needs at least one shape or light, got none"],
        ),
        (
            format!("{{ {GREY}, \"shapes\": {{}} }}"),
            &["bad.json: line 1 column ", "missing field \"camera\""],
        ),
        (
            format!(
                "{{ {CAMERA}, \"materials\": {{ \"grey\": {{}}, \"grey\": {{}} }}, \"lights\": {{}} }}"
            ),
            &[
                "bad.json: line 1 column ",
                "materials: duplicate name \"grey\"",
            ],
        ),
        (
            format!("{} trailing", with_material("{}")),
            &["bad.json: line 2 column ", "trailing characters"],
        ),
    ];
    let mut failures = Vec::new();
    for (text, pieces) in &cases {
        let msg = match illum::scene::from_json_str(text, "bad.json", Path::new(".")) {
            Ok(_) => "<loaded without error>".to_owned(),
            Err(e) => e.to_string(),
        };
        for piece in pieces.iter() {
            if !msg.contains(piece) {
                failures.push(format!("expected  {piece}\n     got  {msg}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn missing_and_unsupported_files() {
    let dir = temp_dir("missing-files");
    let err = |body: &str| load_in(&dir, body).unwrap_err().to_string();
    assert_eq!(
        err(
            r#""textures": { "wood": { "file": "wood.png" } }, "lights": { "env": { "dome": {} } }"#
        ),
        "bad.json: textures.wood.file: cannot read \"wood.png\": No such file or directory"
    );
    assert_eq!(
        err(r#""textures": { "t": { "file": "a.tga" } }, "lights": { "env": { "dome": {} } }"#),
        "bad.json: textures.t.file: unsupported image format \
         (expected .png, .jpg, .jpeg, .exr or .hdr), got \"a.tga\""
    );
    std::fs::write(dir.join("broken.png"), b"\x89PNG not really").unwrap();
    assert_error(
        &format!(
            "{{ {CAMERA}, \"textures\": {{ \"t\": {{ \"file\": \"{}\" }} }}, \"lights\": {{ \"env\": {{ \"dome\": {{}} }} }} }}",
            dir.join("broken.png").display()
        ),
        &[
            "bad.json: textures.t.file: cannot decode \"",
            "broken.png\": ",
        ],
    );
    assert_eq!(
        err(r#""shapes": { "car": { "gltf": { "file": "car.glb" } } }"#),
        "bad.json: shapes.car.gltf.file: cannot read \"car.glb\": No such file or directory"
    );
}
