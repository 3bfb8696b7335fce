//! Control variates (glsl/direct/control_variates.glsl; docs/techniques.md, "Control variates"): `avgvis`
//! and `loo`.
//!
//! * Zero variance: a diffuse plane fully lit by a huge rect, disk, sphere or triangle light, a
//!   wide sun, or a rect with a uniform texture (the control's mean radiance). Each light
//!   sample's diffuse term then has the analytic sum G = rho L E/(pi L), which the control adds
//!   for every sample, so every camera sample equals G(p) exactly. The lights are so large that
//!   G varies by less than 1e-4 over the view, and E/(pi L) below the centre is known in closed
//!   form (rect: corner form factors; disk: R^2/(h^2+R^2); sphere: sin^2 sigma; triangle: Lambert's
//!   polygon formula in f64; sun: cos theta / pi while the cone is above the horizon): each pixel equals
//!   rho L E/(pi L) to that precision for every seed, while the plain estimator's pixels scatter.
//!   The plain estimator's mean matches it too (G is the integral of what g samples).
//! * Unbiased (loo): block means of independent renders against the plain estimator on a
//!   penumbra, Welch t-tests with variances from the renders' scatter, Šidák over the blocks; also
//!   under a rect with a non-uniform texture, whose control uses its mean radiance.
//! * Lights picked from the light tree take no control (one sample per pick): an image with more
//!   lights than the loop threshold is bit-identical with and without `--control-variates`.

mod common;
use common::*;
use illum::integrators::{ControlVariates, Direct, DirectLighting, Technique};
use illum::render::{RenderOutput, RenderSettings, Renderer};
use illum::scene::{Scene, Texture};

const W: u32 = 24;
const H: u32 = 16;
const ALBEDO: f64 = 0.5;
const RADIANCE: f64 = 2.0;

fn settings(cv: ControlVariates, spp: u32) -> RenderSettings {
    RenderSettings {
        spp,
        trace: trace_mode(),
        integrator: Direct(DirectLighting {
            technique: Technique::Mis,
            light_samples: 4,
            control_variates: cv,
            ..Default::default()
        })
        .into(),
        ..Default::default()
    }
}

/// The floor scene with `light` as the only light ("" for none: `shapes` then holds the
/// emitter), `shapes` more shapes (each ", name: {...}").
fn floor_scene(light: &str, shapes: &str) -> String {
    let lights = if light.is_empty() {
        String::new()
    } else {
        format!(
            r#""key": {{{light}, "color": [{RADIANCE}, {RADIANCE}, {RADIANCE}], "intensity": 1}}"#
        )
    };
    format!(
        r#"{{"camera": {{"position": [0, 0.3, 0], "look_at": [0, 0, 0], "up": [0, 0, 1], "fov_y": 60, "resolution": [{W}, {H}]}},
        "materials": {{"m": {{"diffuse": [{ALBEDO}, {ALBEDO}, {ALBEDO}]}}, "e": {{"diffuse": [0, 0, 0], "emission": [{RADIANCE}, {RADIANCE}, {RADIANCE}]}}}},
        "shapes": {{"floor": {{"rect": {{"center": [0, 0, 0], "normal": [0, 1, 0], "size": [40, 40]}}, "material": "m"}}{shapes}}},
        "lights": {{{lights}}}}}"#
    )
}

fn scene_json(light: &str, occluder: bool) -> String {
    let sphere = if occluder {
        r#", "ball": {"sphere": {"center": [0.35, 0.5, 0], "radius": 0.25}, "material": "m"}"#
    } else {
        ""
    };
    floor_scene(light, sphere)
}

/// An emissive triangle at height 1 facing down, centroid above the origin, circumradius 34.64.
const TRIANGLE: [[f64; 3]; 3] = [[-30.0, 1.0, -17.32], [30.0, 1.0, -17.32], [0.0, 1.0, 34.64]];

fn triangle_shape() -> String {
    let p = TRIANGLE
        .map(|v| format!("[{}, {}, {}]", v[0], v[1], v[2]))
        .join(", ");
    format!(r#", "tri": {{"mesh": {{"positions": [{p}]}}, "material": "e"}}"#)
}

/// E / (pi L) at the origin (normal +Y) of the polygon `v` above it (Lambert's formula, f64).
fn polygon_form_factor(v: &[[f64; 3]]) -> f64 {
    let q: Vec<glam::DVec3> = v
        .iter()
        .map(|p| glam::DVec3::from(*p).normalize())
        .collect();
    let mut sum = 0.0;
    for k in 0..q.len() {
        let (a, b) = (q[k], q[(k + 1) % q.len()]);
        let c = a.cross(b);
        sum += c.length().atan2(a.dot(b)) * c.normalize().y;
    }
    sum.abs() / (2.0 * std::f64::consts::PI)
}

/// The scene of `json` with its light textured by a 2 x 2 bilinear texture of grey `texels`.
fn textured(json: &str, texels: [f32; 4]) -> Scene {
    let mut sc = scene(json);
    let t = texels.map(|v| glam::Vec4::new(v, v, v, 1.0)).to_vec();
    sc.textures.push(Texture::new("t", 2, 2, t));
    sc.lights[0].texture = Some(sc.textures.len() as u32 - 1);
    sc
}

/// The emissive triangle scaled by `scale` about the Y axis, with uvs (0, 0), (1, 0), (0.5, 1)
/// and its emission textured by a 2 x 2 bilinear texture of grey `texels`; `shapes` more shapes.
fn textured_triangle(scale: f64, shapes: &str, texels: [f32; 4]) -> Scene {
    let p = TRIANGLE
        .map(|v| format!("[{}, {}, {}]", v[0] * scale, v[1], v[2] * scale))
        .join(", ");
    let tri = format!(
        r#", "tri": {{"mesh": {{"positions": [{p}], "uvs": [[0, 0], [1, 0], [0.5, 1]]}}, "material": "e"}}{shapes}"#
    );
    let mut sc = scene(&floor_scene("", &tri));
    let t = texels.map(|v| glam::Vec4::new(v, v, v, 1.0)).to_vec();
    sc.textures.push(Texture::new("t", 2, 2, t));
    let e = sc.materials.iter().position(|m| m.name == "e").unwrap();
    sc.materials[e].emission_texture = Some(sc.textures.len() as u32 - 1);
    sc
}

fn render(renderer: &Renderer, json: &str, s: &RenderSettings, seeds: &[u64]) -> Vec<RenderOutput> {
    render_seeds(renderer, &scene(json), s, seeds)
}

#[test]
fn fully_lit_plane_has_zero_variance() {
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    // E / (pi L) straight below the centre: a rect's four corner form factors, a disk's
    // R^2 / (h^2 + R^2), a sphere's sin^2(sigma); then how far a pixel may be from it. Over the
    // view (up to rho = 0.31 from the centre) the rect's and disk's change by less than 1e-5; the
    // sphere's, sin^2(sigma) cos(theta) = d0^2 / (d0^2 + rho^2) cos(theta), by up to
    // 1.5 rho^2 / d0^2 = 3.3e-4 (d0 = 21).
    let corner = |a: f64, b: f64| {
        let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
        (a / sa * (b / sa).atan() + b / sb * (a / sb).atan()) / (2.0 * std::f64::consts::PI)
    };
    // A wide sun (90 degrees across, 2 samples of 4) 30 degrees from the zenith: its cone stays
    // above the horizon, E = E_perp cos 30. The triangle, like the rect, changes by < 1e-5 over
    // the view. The textured rect: a uniform 0.7 texture, so its mean radiance is 0.7 L.
    let sun = r#""sun": {"direction": [0.5, 0.8660254037844386, 0], "angular_diameter": 90}"#;
    let rect = r#""rect": {"center": [0, 1, 0], "normal": [0, -1, 0], "size": [40, 40]}"#;
    let cases = [
        (
            "sun",
            sun.to_string(),
            0.8660254037844386 / std::f64::consts::PI,
            1e-5,
        ),
        (
            "triangle",
            String::new(),
            polygon_form_factor(&TRIANGLE),
            1e-4,
        ),
        (
            "textured rect",
            rect.to_string(),
            0.7 * 4.0 * corner(20.0, 20.0),
            1e-4,
        ),
        (
            "textured triangle",
            String::new(),
            0.7 * polygon_form_factor(&TRIANGLE),
            1e-4,
        ),
        (
            "rect",
            r#""rect": {"center": [0, 1, 0], "normal": [0, -1, 0], "size": [40, 40]}"#.to_string(),
            4.0 * corner(20.0, 20.0),
            1e-4,
        ),
        (
            "disk",
            r#""disk": {"center": [0, 1, 0], "normal": [0, -1, 0], "radius": 20}"#.to_string(),
            400.0 / 401.0,
            1e-4,
        ),
        (
            "sphere",
            r#""sphere": {"center": [0, 21, 0], "radius": 20}"#.to_string(),
            (20.0f64 / 21.0).powi(2),
            4e-4,
        ),
    ];
    for (name, light, share, tolerance) in cases {
        let sc = match name {
            "triangle" => scene(&floor_scene("", &triangle_shape())),
            "textured rect" => textured(&scene_json(&light, false), [0.7; 4]),
            "textured triangle" => textured_triangle(1.0, "", [0.7; 4]),
            _ => scene(&scene_json(&light, false)),
        };
        let expected = ALBEDO * RADIANCE * share;
        // Both forms share G and Lc; the lights added later test one (each render compiles a
        // kernel: CI time).
        let forms: &[ControlVariates] = if matches!(name, "rect" | "disk" | "sphere") {
            &[ControlVariates::AvgVis, ControlVariates::Loo]
        } else {
            &[ControlVariates::Loo]
        };
        for &cv in forms {
            let outs = render_seeds(&renderer, &sc, &settings(cv, 2), &[3, 4]);
            let mut worst = 0.0f64;
            for o in &outs {
                for p in &o.film.beauty {
                    worst = worst.max((luminance(*p) / expected - 1.0).abs());
                }
            }
            eprintln!(
                "{name} {}: largest |pixel / expected - 1| = {worst:.2e}",
                cv.name()
            );
            assert!(
                worst < tolerance,
                "{name} {}: a pixel is {worst:.2e} off rho L sin^2",
                cv.name()
            );
        }
        // The plain estimator on the same plane: unbiased, but its pixels scatter (the test
        // above would fail for it). Only for the shapes that share one kernel: each new scene
        // feature costs a kernel compile (CI time).
        if !matches!(name, "rect" | "disk" | "sphere") {
            continue;
        }
        let plain = render_seeds(&renderer, &sc, &settings(ControlVariates::Off, 2), &[1, 2]);
        // Its mean, with the standard error from the scatter of its (independent) pixels.
        let xs: Vec<f64> = plain
            .iter()
            .flat_map(|o| o.film.beauty.iter().map(|p| luminance(*p)))
            .collect();
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let se = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        let worst = xs
            .iter()
            .map(|x| (x / expected - 1.0).abs())
            .fold(0.0, f64::max);
        eprintln!(
            "{name} plain: largest |pixel / expected - 1| = {worst:.2e}, mean {mean:.5} ± {se:.5} vs {expected:.5}"
        );
        assert!(worst > 1e-2, "{name}: the plain estimator should scatter");
        assert!(
            (mean - expected).abs() <= 5.0 * se,
            "{name}: plain mean {mean} ± {se} vs {expected}"
        );
    }
    assert_no_validation_messages(&ctx);
}

/// Mean and variance of the mean over the seeds, per 4x4 block, then for the whole image.
fn stats(outs: &[RenderOutput]) -> Vec<(f64, f64)> {
    block_stats(outs, 4)
}

#[test]
fn leave_one_out_is_unbiased_in_a_penumbra() {
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    let json = scene_json(
        r#""rect": {"center": [0, 1, 0], "normal": [0, -1, 0], "size": [8, 8]}"#,
        true,
    );
    // The textured lights: a 2 x 2 checker of 1 and 0.1, bilinear (mean 0.55 on the rect); the
    // triangle (0.15 of the zero-variance one, 1 above the floor) over the same ball.
    let ball =
        r#", "ball": {"sphere": {"center": [0.35, 0.5, 0], "radius": 0.25}, "material": "m"}"#;
    let scenes = [
        ("rect", scene(&json)),
        ("textured rect", textured(&json, [1.0, 0.1, 0.1, 1.0])),
        (
            "textured triangle",
            textured_triangle(0.15, ball, [1.0, 0.1, 0.1, 1.0]),
        ),
    ];
    let seeds = |base: u64| (0..16).map(|j| base * 64 + j).collect::<Vec<u64>>();
    for (c, (name, sc)) in scenes.iter().enumerate() {
        let base = 1 + 2 * c as u64;
        let plain = stats(&render_seeds(
            &renderer,
            sc,
            &settings(ControlVariates::Off, 4),
            &seeds(base),
        ));
        let loo = stats(&render_seeds(
            &renderer,
            sc,
            &settings(ControlVariates::Loo, 4),
            &seeds(base + 1),
        ));
        // Šidák over the blocks of both scenes.
        let per = 1.0 - (1.0 - 1e-3f64).powf(1.0 / (scenes.len() * loo.len()) as f64);
        let (mut vp, mut vl) = (0.0, 0.0);
        for (b, (&(m1, v1), &(m0, v0))) in loo.iter().zip(&plain).enumerate() {
            let t = t_for(per, welch_dof(&[(v1, 15.0), (v0, 15.0)]));
            let se = (v1 + v0).sqrt();
            vp += v0;
            vl += v1;
            assert!(
                (m1 - m0).abs() <= t * se,
                "{name} loo: block {b}: {m1} vs plain {m0} (t = {:.2}, limit {t:.2})",
                (m1 - m0) / se
            );
        }
        eprintln!(
            "{name}: variance of the block means: loo / plain = {:.3}",
            vl / vp
        );
    }
    assert_no_validation_messages(&ctx);
}

#[test]
fn fully_shadowed_plane_is_black() {
    // A 40x40 opaque sheet between the camera (below it) and the 8x8 rect light: every shadow ray
    // of every floor point is blocked, so the visibility estimate is 0 and so is the control's
    // term: the pixels are exactly 0, for both forms (without the visibility factor, the control
    // would add G).
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    let json = scene_json(
        r#""rect": {"center": [0, 1, 0], "normal": [0, -1, 0], "size": [8, 8]}"#,
        false,
    )
    .replace(
        r#""material": "m"}}"#,
        r#""material": "m"}, "sheet": {"rect": {"center": [0, 0.5, 0], "normal": [0, -1, 0], "size": [40, 40]}, "material": "m"}}"#,
    );
    assert!(json.contains("sheet"));
    for cv in [ControlVariates::AvgVis, ControlVariates::Loo] {
        let outs = render(&renderer, &json, &settings(cv, 2), &[5, 6]);
        assert_shadowed_black(&outs, W, H, cv.name());
    }
    assert_no_validation_messages(&ctx);
}

#[test]
fn lights_picked_from_the_tree_take_no_control() {
    // 72 small sphere lights (above the 64-light loop threshold): the light samples pick lights
    // from the tree, one per sample, where the per-light control does not apply (see
    // docs/control-variates.md), so the control variates change nothing, bit for bit.
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    let lights: Vec<String> = (0..72)
        .map(|i| {
            let (x, z) = (f64::from(i % 8) - 3.5, 0.5 * f64::from(i / 8) - 2.0);
            format!(
                r#""l{i}": {{"sphere": {{"center": [{x}, 1, {z}], "radius": 0.1}}, "color": [{RADIANCE}, {RADIANCE}, {RADIANCE}]}}"#
            )
        })
        .collect();
    let json = scene_json(
        r#""rect": {"center": [0, 1, 0], "normal": [0, -1, 0], "size": [8, 8]}"#,
        true,
    )
    .replace(
        r#""lights": {"key": "#,
        &format!(r#""lights": {{{}, "key": "#, lights.join(", ")),
    );
    assert!(json.contains("l71"));
    let sc = scene(&json);
    let off = render_seeds(&renderer, &sc, &settings(ControlVariates::Off, 2), &[7]);
    // Loo only: avgvis takes the same branch (each render compiles a kernel: CI time).
    let on = render_seeds(&renderer, &sc, &settings(ControlVariates::Loo, 2), &[7]);
    assert_eq!(
        on[0].film.beauty, off[0].film.beauty,
        "tree-picked lights changed"
    );
    assert_no_validation_messages(&ctx);
}
