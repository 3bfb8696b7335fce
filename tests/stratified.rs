//! Stratified samples (glsl/direct/direct.glsl `group_u`): the light samples of a light and the
//! BRDF samples of a lobe at a shading point, 2^m of them one block of a dimension pair's Sobol
//! points (a net within the group, stratified across camera samples), other counts jittered
//! within the cells of a grid (`stratify`: n strata of a textured dome's rows, its columns in a
//! randomly shifted Latin order). Each estimator
//! alone must stay unbiased, so each is checked against a closed form with several samples per
//! group: light samples only and BRDF samples only on a Lambert floor under a large rect light
//! (the polygon formula), and light samples only under a textured dome (Gauss-Legendre
//! quadrature of its map). Per-pixel and image-mean t-tests over BATCHES independent renders
//! (tests/common), family-wise 0.01.

mod common;
use common::*;
use glam::DVec3;
use illum::integrators::{Direct, DirectLighting, Technique};
use illum::stress::closed_form::dome_irradiance_quadrature;
use std::f64::consts::PI;
use std::path::Path;

const W: u32 = 12;
const H: u32 = 12;
const ALBEDO: f64 = 0.5;
const CAMERA: [f64; 3] = [1.0, 0.3, 0.2];
const FOV_DEG: f64 = 20.0;

/// A Lambert floor under `light`, seen from a camera below the light (its rays never cross it).
fn scene_json(light: &str, textures: &str) -> String {
    let [x, y, z] = CAMERA;
    format!(
        r#"{{"camera": {{"position": [{x}, {y}, {z}], "look_at": [0, 0, 0], "fov_y": {FOV_DEG}, "resolution": [{W}, {H}]}},
            "textures": {{{textures}}},
            "materials": {{"m": {{"diffuse": [{ALBEDO}, {ALBEDO}, {ALBEDO}]}}}},
            "shapes": {{"floor": {{"rect": {{"center": [0, 0, 0], "normal": [0, 1, 0], "size": [40, 40]}}, "material": "m"}}}},
            "lights": {{"l": {light}}}}}"#
    )
}

/// The floor's radiance ALBEDO E / pi for irradiance E(x), averaged over each pixel's points.
fn check(b: &Batches, irradiance: impl Fn(DVec3) -> f64) {
    let pts = floor_points(DVec3::from_array(CAMERA), FOV_DEG, W, H);
    assert_lambert_floor(b, &pts, ALBEDO, irradiance);
}

#[test]
fn stratified_light_and_brdf_samples_match_the_polygon_formula() {
    // A 4 x 4 rect 0.4 above the floor: from the floor under it, share = solid angle / 2 pi is
    // about 0.8, so 4 light samples (one block of 4 points) where the default N_max is 4, 3
    // (a 3 x 1 grid) at 3.
    let (l, h, s) = (2.0, 0.4, 2.0);
    let irradiance = square_light_irradiance(l, h, s);
    let scene = scene(&scene_json(
        &format!(
            r#"{{"rect": {{"center": [0, {h}, 0], "normal": [0, -1, 0], "size": [{}, {}]}}, "intensity": {l}}}"#,
            2.0 * s,
            2.0 * s
        ),
        "",
    ));
    for (technique, light_samples, brdf_samples) in [
        (Technique::Light, 4, 1),
        (Technique::Light, 3, 1),
        (Technique::Brdf, 4, 4),
    ] {
        eprintln!("{technique:?}, {light_samples} light samples, {brdf_samples} BRDF samples");
        let integrator = Direct(DirectLighting {
            technique,
            light_samples,
            brdf_samples,
            ..Default::default()
        });
        // 256 spp: 16 camera samples per batch. A BRDF sample's estimate is nearly binary here
        // (hit the light or not), so each batch mean needs enough of them to be near normal for
        // the t-tests (at 4 camera samples, a pixel that happened to miss rarely failed at t = 7).
        check(&render_batches_with(&scene, integrator, 256, 3), irradiance);
    }
}

#[test]
fn stratified_dome_samples_match_the_quadrature_of_the_map() {
    // scenes/bench/sky.exr: a sky with a small sun ~2000 x brighter. Unoccluded, the floor's
    // irradiance is the same everywhere.
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bench");
    let json = scene_json(
        r#"{"dome": {}, "texture": "sky", "visible": false}"#,
        r#""sky": {"file": "sky.exr"}"#,
    );
    let scene = illum::scene::from_json_str(&json, "<test scene>", &dir).expect("test scene");
    let light = &scene.lights[0];
    let illum::scene::LightKind::Dome {
        rotation_deg,
        convention,
    } = light.kind
    else {
        panic!("not a dome")
    };
    let texture = &scene.textures[light.texture.expect("textured") as usize];
    let radiance = light.radiance();
    let e = dome_irradiance_quadrature(texture, rotation_deg, convention, DVec3::Y)
        * DVec3::new(radiance.x.into(), radiance.y.into(), radiance.z.into());
    assert!(e.min_element() > 0.0);
    // A textured dome takes 2 N_max samples: 8 (one block of points) at N_max 4, 6 row strata
    // with shifted columns at 3.
    for light_samples in [4, 3] {
        let integrator = Direct(DirectLighting {
            technique: Technique::Light,
            light_samples,
            ..Default::default()
        });
        let b = render_batches_with(&scene, integrator, 256, 6);
        assert_matches_expectation(&b, |_| (ALBEDO * e / PI).to_array(), 0.01);
    }
}
