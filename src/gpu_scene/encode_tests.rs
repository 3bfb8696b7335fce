//! The features the encoding gives a scene (its dome, its materials), on the host.

use super::*;

/// The scene's features with a dome of `dome` (JSON) textured or not by `sky.exr` of
/// scenes/bench with `filter`.
fn features(dome: &str, texture: bool, filter: &str) -> u32 {
    let light = if texture {
        format!(r#"{{"dome": {dome}, "texture": "sky"}}"#)
    } else {
        format!(r#"{{"dome": {dome}}}"#)
    };
    let json = format!(
        r#"{{"camera": {{"position": [0, 1, 4], "look_at": [0, 0, 0], "fov_y": 40, "resolution": [8, 8]}},
            "textures": {{"sky": {{"file": "sky.exr", "filter": "{filter}"}}}},
            "materials": {{"m": {{"diffuse": [0.5, 0.5, 0.5]}}}},
            "shapes": {{"s": {{"sphere": {{"center": [0, 0, 0], "radius": 1}}, "material": "m"}}}},
            "lights": {{"sky": {light}}}}}"#
    );
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bench");
    let scene = crate::scene::from_json_str(&json, "test", &dir).unwrap();
    encode_scene(&scene, DVec3::ZERO, true).unwrap().features
}

#[test]
fn shaped_dome_cells_are_a_feature_of_the_lookup() {
    let shaped = |f: u32| f & FEATURE_DOME_SHAPED != 0;
    assert!(shaped(features(
        r#"{"convention": "mitsuba"}"#,
        true,
        "bilinear"
    )));
    assert!(shaped(features("{}", true, "bilinear")));
    assert!(!shaped(features("{}", true, "nearest")));
    assert!(!shaped(features("{}", false, "bilinear")));
    assert!(features("{}", false, "bilinear") & FEATURE_DOME != 0);
}

/// The features of a scene whose one sphere has material `material` (JSON).
fn material_features(material: &str) -> u32 {
    let json = format!(
        r#"{{"camera": {{"position": [0, 1, 4], "look_at": [0, 0, 0], "fov_y": 40, "resolution": [8, 8]}},
            "materials": {{"m": {material}}},
            "shapes": {{"s": {{"sphere": {{"center": [0, 0, 0], "radius": 1}}, "material": "m"}}}},
            "lights": {{"sky": {{"dome": {{}}}}}}}}"#
    );
    let scene = crate::scene::from_json_str(&json, "test", std::path::Path::new(".")).unwrap();
    encode_scene(&scene, DVec3::ZERO, true).unwrap().features
}

#[test]
fn ggx_code_is_a_feature_of_the_materials() {
    let ggx = |m: &str| material_features(m) & FEATURE_GGX != 0;
    let lobe = |model: &str| {
        format!(
            r#"{{"diffuse": [0.2, 0.2, 0.2], "specular": [{{"model": "{model}", "roughness": 0.2,
                "fresnel": {{"schlick": [0.04, 0.04, 0.04]}}}}]}}"#
        )
    };
    assert!(ggx(&lobe("ggx")));
    assert!(!ggx(&lobe("beckmann")));
    assert!(!ggx(&lobe("dbrdf")));
    assert!(!ggx(r#"{"diffuse": [0.5, 0.5, 0.5]}"#));
}

/// Where a dome's light samples read its texels: the map's offset in the texel buffer (the
/// textures one after the other), under the Mitsuba convention only where a cell's two corner
/// rows exist (a one-row map has none below its first).
#[test]
fn a_mitsuba_dome_finds_its_texels_after_the_textures_before_it() {
    use crate::scene::Texture;
    use glam::Vec4;
    let json = r#"{"camera": {"position": [0, 1, 4], "look_at": [0, 0, 0], "fov_y": 40, "resolution": [8, 8]},
        "textures": {"sky": {"file": "sky.exr"}},
        "materials": {"m": {"diffuse": [0.5, 0.5, 0.5]}},
        "shapes": {"s": {"sphere": {"center": [0, 0, 0], "radius": 1}, "material": "m"}},
        "lights": {"sky": {"dome": {"convention": "mitsuba"}, "texture": "sky"}}}"#;
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bench");
    let mut scene = crate::scene::from_json_str(json, "test", &dir).unwrap();
    let first = scene.textures[0].texels.len() as u64;
    let offset = |scene: &Scene| {
        encode_scene(scene, DVec3::ZERO, true)
            .unwrap()
            .dome_table
            .unwrap()
            .texel_offset
    };
    assert_eq!(offset(&scene), Some(0));
    let light = scene
        .lights
        .iter()
        .position(|l| l.texture.is_some())
        .unwrap();
    for (h, expected) in [(3, Some(first)), (1, None)] {
        let map = Texture::new(
            "map",
            4,
            h,
            vec![Vec4::new(1.0, 0.5, 0.25, 1.0); 4 * h as usize],
        );
        scene.textures.truncate(1);
        scene.textures.push(map);
        scene.lights[light].texture = Some(1);
        assert_eq!(offset(&scene), expected, "a map of {h} rows");
    }
}
