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

/// A box from its centre and half extents.
fn aabb(c: [f32; 3], h: [f32; 3]) -> [f32; 6] {
    [
        c[0] - h[0],
        c[1] - h[1],
        c[2] - h[2],
        c[0] + h[0],
        c[1] + h[1],
        c[2] + h[2],
    ]
}

#[test]
fn a_closed_room_is_traced_flat_and_spread_small_shapes_are_not() {
    // The six walls of a 4 x 3 x 5 room and two spheres in it: each wall's box is a large share
    // of the room's, so a ray's BVH walk would test most of them anyway.
    let mut room = vec![
        aabb([0.0, 0.0, 0.0], [2.0, 0.0, 2.5]),
        aabb([0.0, 3.0, 0.0], [2.0, 0.0, 2.5]),
        aabb([-2.0, 1.5, 0.0], [0.0, 1.5, 2.5]),
        aabb([2.0, 1.5, 0.0], [0.0, 1.5, 2.5]),
        aabb([0.0, 1.5, -2.5], [2.0, 1.5, 0.0]),
        aabb([0.0, 1.5, 2.5], [2.0, 1.5, 0.0]),
        aabb([-1.0, 0.5, 0.0], [0.5, 0.5, 0.5]),
        aabb([1.0, 0.5, -1.0], [0.5, 0.5, 0.5]),
    ];
    assert!(flat_shapes(&room));
    // Eight small spheres spread over a large floor: the walk skips most of them.
    let mut spread: Vec<[f32; 6]> = (0..8)
        .map(|i| aabb([3.0 * i as f32, 0.5, 0.0], [0.5, 0.5, 0.5]))
        .collect();
    assert!(!flat_shapes(&spread));
    spread.push(aabb([10.5, 0.0, 0.0], [11.0, 0.0, 11.0]));
    assert!(!flat_shapes(&spread), "one large floor among small shapes");
    // More shapes than the flat copy holds, and none.
    while room.len() <= BVH_FLAT_MAX as usize {
        room.push(room[0]);
    }
    assert!(!flat_shapes(&room));
    assert!(!flat_shapes(&[]));
}
