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
