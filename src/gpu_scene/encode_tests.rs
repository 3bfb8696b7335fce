//! The features the encoding gives a scene's dome, on the host.

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
