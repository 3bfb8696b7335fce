//! The stress suite (scenes/stress, src/stress): every case renders on both trace paths (ray
//! queries only where the device has them) with zero non-finite samples and no validation
//! message, and its image mean agrees with its reference: the float64 closed form, or a render by
//! a different technique (light sampling against the MIS under test). The firefly clamp is off by
//! default and, when on, counts the samples it changed.
//!
//! Each comparison is a z-test on the image mean (standard error from the Variance AOV, plus a
//! 1e-5 relative floor for float32 accumulation), at a family-wise level of 1e-3 over every case
//! and path (Šidák).
//!
//! The glossy cases whose reference is another technique of the same renderer (a BRDF bug both
//! share would pass) are also checked per pixel against an independent float64 integral of the
//! BRDF over the lights (`stress/reference.rs`), with the standard error estimated from
//! independent pixel means, not from the renderer's Variance AOV.

mod common;
#[path = "stress/reference.rs"]
mod reference;
use common::*;
use illum::integrators::{Direct, DirectLighting, Technique};
use illum::render::{RenderSettings, Renderer};
use illum::stress::{CASES, Case, FLOAT_FLOOR, Reference, mean_luminance};
use illum::trace::TraceMode;
use std::path::Path;

const SIZE: u32 = 24;
const SPP: u32 = 128;
const REFERENCE_SPP: u32 = 512;

fn stress_dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/stress")
}

/// A stress case and its scene, rendered at w × h.
fn load_case(name: &str, w: u32, h: u32) -> (&'static Case, illum::scene::Scene) {
    let case = CASES.iter().find(|c| c.name == name).expect("case listed");
    let mut scene = case
        .load(&stress_dir())
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    scene.camera.width = w;
    scene.camera.height = h;
    (case, scene)
}

fn run_case(name: &str) {
    let (case, scene) = load_case(name, SIZE, SIZE);
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    assert!(
        scene.description.as_deref().is_some_and(|d| !d.is_empty()),
        "{name}: the scene must say what is extreme"
    );
    let reference = case
        .reference(&renderer, &scene, REFERENCE_SPP)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let (ref_mean, ref_se) = mean_luminance(&reference.image, reference.variance.as_deref());
    assert!(ref_mean > 0.0, "{name}: black reference");
    let mut paths = vec![TraceMode::Bvh];
    if TraceMode::RayQuery.resolve(&ctx).is_ok() {
        paths.push(TraceMode::RayQuery);
    } else {
        eprintln!("{name}: no ray queries on this device: BVH only");
    }
    let tests = (CASES.len() * 2) as f64;
    let z_max = z_for(1.0 - (1.0 - 1e-3f64).powf(1.0 / tests));
    for trace in paths {
        let settings = RenderSettings {
            spp: SPP,
            seed: 7,
            trace,
            integrator: Direct(DirectLighting {
                technique: Technique::Mis,
                ..Default::default()
            })
            .into(),
            ..Default::default()
        };
        let out = renderer
            .render(&scene, &settings, &mut |_, _| {})
            .unwrap_or_else(|e| panic!("{name} ({trace:?}): {e}"));
        assert_eq!(
            out.stats.non_finite_samples, 0,
            "{name} ({}): non-finite samples",
            out.stats.trace
        );
        assert!(
            out.film.beauty.iter().flatten().all(|c| c.is_finite()),
            "{name}: non-finite pixel"
        );
        let (mean, se) = mean_luminance(&out.film.beauty, out.film.variance.as_deref());
        let sigma = se.hypot(ref_se).hypot(FLOAT_FLOOR * ref_mean);
        let z = (mean - ref_mean) / sigma;
        eprintln!(
            "{name} ({}): mean {mean:.6e}, reference {ref_mean:.6e} ({}), ratio {:.5}, z {z:+.2} (limit {z_max:.2})",
            out.stats.trace,
            reference.what,
            mean / ref_mean
        );
        assert!(
            z.abs() < z_max,
            "{name} ({}): image mean {mean} vs reference {ref_mean} ({}): z = {z:.2}",
            out.stats.trace,
            reference.what
        );
    }
    assert_no_validation_messages(&ctx);
}

macro_rules! cases {
    ($($test:ident => $name:literal),* $(,)?) => {
        $(#[test] fn $test() { run_case($name); })*

        /// Every case in CASES has a test here, and every scene file a case.
        #[test]
        fn every_case_is_tested_and_every_scene_listed() {
            let tested = [$($name),*];
            for c in CASES {
                assert!(tested.contains(&c.name), "case {} has no test", c.name);
            }
            for e in std::fs::read_dir(stress_dir()).unwrap() {
                let p = e.unwrap().path();
                if p.extension().is_some_and(|x| x == "json") {
                    let stem = p.file_stem().unwrap().to_string_lossy().to_string();
                    assert!(CASES.iter().any(|c| c.name == stem), "{stem}.json is not a case");
                }
            }
        }
    };
}

cases! {
    microfacet_alpha_1e_4 => "microfacet-alpha-1e-4",
    microfacet_alpha_1e_3 => "microfacet-alpha-1e-3",
    microfacet_alpha_1 => "microfacet-alpha-1",
    anisotropic_100 => "anisotropic-100",
    grazing_diffuse => "grazing-diffuse",
    grazing_glossy => "grazing-glossy",
    sphere_light_tiny => "sphere-light-tiny",
    sphere_light_touching => "sphere-light-touching",
    rect_light_huge_far => "rect-light-huge-far",
    rect_light_huge_near => "rect-light-huge-near",
    disk_light_huge_near => "disk-light-huge-near",
    emitter_huge_near => "emitter-huge-near",
    far_from_origin => "far-from-origin",
    dome_hot_pixel => "dome-hot-pixel",
    triangles_degenerate => "triangles-degenerate",
    lights_zero => "lights-zero",
    sun_delta => "sun-delta",
    sun_30deg => "sun-30deg",
}

/// The closed forms are the right ones for their scenes: a scene the evaluator cannot do exactly
/// (a sphere occluder) is refused, not approximated.
#[test]
fn closed_form_refuses_what_it_cannot_do() {
    let s = scene(
        r#"{"camera": {"position": [0, 2, 2], "look_at": [0, 0, 0], "fov_y": 60, "resolution": [8, 8]},
            "materials": {"m": {"diffuse": [0.5, 0.5, 0.5]}},
            "shapes": {"floor": {"rect": {"center": [0, 0, 0], "normal": [0, 1, 0], "size": [9, 9]}, "material": "m"},
                       "ball": {"sphere": {"center": [0, 1, 0], "radius": 0.5}, "material": "m"}},
            "lights": {"sun": {"sun": {"direction": [0, 1, 0]}}}}"#,
    );
    let e = illum::stress::closed_form::image(&s).unwrap_err();
    assert!(e.contains("only rects and meshes"), "{e}");
    assert!(CASES.iter().any(|c| c.reference == Reference::ClosedForm));
}

/// Emitters that nearly fill the receiver's hemisphere (a 4000-wide rect, a radius-20 disk seen at
/// its rim, a 200-wide emissive quad, all 1 above the floor): every light sample is bounded, as
/// the light sampler's pdf promises (glsl/lights/light_sampling.glsl): at least 1 / (4 pi) per
/// steradian over the emitter for the planar mixture, 1 / (2 pi) for a rect (hemisphere or
/// spherical rect), so a Lambert floor of albedo ρ under radiance L gets ρ/π L cos / pdf ≤ 4 ρ L
/// (2 ρ L) per sample. At 1 spp a pixel is one camera sample. Area sampling alone gave samples of
/// up to ρ/π L A / d² (before the change: 2.97 under the rect, 62 under the disk).
#[test]
fn huge_emitters_near_the_floor_give_bounded_samples() {
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    // pdf ≥ 1 / (2 pi) for a rect (hemisphere or spherical rect), ≥ 1 / (4 pi) for the mixture.
    for (name, per_emitter) in [
        ("rect-light-huge-near", 2.0),
        ("disk-light-huge-near", 4.0),
        ("emitter-huge-near", 4.0),
    ] {
        let (_, scene) = load_case(name, 32, 32);
        let rho = scene
            .materials
            .iter()
            .map(|m| m.diffuse.max_element())
            .fold(0.0f32, f32::max);
        let radiance = scene
            .lights
            .iter()
            .map(|l| l.radiance().max_element())
            .chain(scene.materials.iter().map(|m| m.emission.max_element()))
            .fold(0.0f32, f32::max);
        // Each emitter (a light, or one emissive triangle, all looped over below 32) adds its own
        // bounded estimate.
        let emitters = scene.lights.len()
            + scene
                .meshes
                .iter()
                .filter(|m| scene.materials[m.material as usize].emission.max_element() > 0.0)
                .map(|m| m.indices.len() / 3)
                .sum::<usize>();
        let bound = per_emitter * rho * radiance * emitters as f32;
        let settings = RenderSettings {
            spp: 1,
            seed: 3,
            trace: trace_mode(),
            integrator: Direct(DirectLighting {
                technique: Technique::Light,
                ..Default::default()
            })
            .into(),
            ..Default::default()
        };
        let out = renderer
            .render(&scene, &settings, &mut |_, _| {})
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let max = out
            .film
            .beauty
            .iter()
            .flatten()
            .fold(0.0f32, |m, &c| m.max(c));
        eprintln!("{name}: largest 1-spp pixel {max:.4}, bound {bound:.4}");
        assert!(
            max > 0.0 && max <= bound * (1.0 + 1e-5),
            "{name}: a 1-spp pixel of {max} above {emitters} × {per_emitter} ρ L = {bound}"
        );
    }
    assert_no_validation_messages(&ctx);
}

/// The firefly clamp: off by default (nothing clamped), and when on it lowers a tiny bright
/// light's image, never above the clamp per sample, and counts what it clamped.
#[test]
fn firefly_clamp_is_off_by_default_and_counted_when_on() {
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    let (_, scene) = load_case("sphere-light-tiny", 16, 16);
    let base = RenderSettings {
        spp: 8,
        trace: trace_mode(),
        ..Default::default()
    };
    let off = renderer.render(&scene, &base, &mut |_, _| {}).unwrap();
    assert_eq!(off.stats.clamped_samples, 0);
    let clamp = 0.05f32;
    let on = renderer
        .render(
            &scene,
            &RenderSettings {
                clamp: Some(clamp),
                ..base.clone()
            },
            &mut |_, _| {},
        )
        .unwrap();
    assert!(on.stats.clamped_samples > 0);
    let lum = |p: &[f32; 3]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    for (a, b) in on.film.beauty.iter().zip(&off.film.beauty) {
        assert!(
            lum(a) <= clamp * 1.0001,
            "clamped pixel {a:?} above {clamp}"
        );
        assert!(lum(a) <= lum(b) * 1.0001);
    }
    let bad = renderer.render(
        &scene,
        &RenderSettings {
            clamp: Some(f32::NAN),
            ..base
        },
        &mut |_, _| {},
    );
    assert!(bad.is_err_and(|e| e.to_string().contains("--clamp")));
    assert_no_validation_messages(&ctx);
}

/// Non-finite samples are counted at one place and kept out of the image: with every third
/// sample made NaN (the test hook), the count is exact and each such sample counts as 0, so the
/// image stays finite and its mean is 2/3 of the clean one.
#[test]
fn non_finite_samples_are_counted_and_kept_out_of_the_image() {
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    let (_, scene) = load_case("sun-delta", 8, 4);
    let settings = RenderSettings {
        spp: 9,
        trace: trace_mode(),
        inject_non_finite: 3,
        ..Default::default()
    };
    let out = renderer.render(&scene, &settings, &mut |_, _| {}).unwrap();
    // Samples 0, 3 and 6 of each of the 32 pixels.
    assert_eq!(out.stats.non_finite_samples, 3 * 32);
    let clean = renderer
        .render(
            &scene,
            &RenderSettings {
                inject_non_finite: 0,
                ..settings
            },
            &mut |_, _| {},
        )
        .unwrap();
    assert_eq!(clean.stats.non_finite_samples, 0);
    for (a, b) in out.film.beauty.iter().zip(&clean.film.beauty) {
        for c in 0..3 {
            assert!(a[c].is_finite());
            // A delta sun on a plane: every sample has nearly the same value, so dropping a
            // third of them scales the mean by 2/3.
            assert!(
                (a[c] - b[c] * 2.0 / 3.0).abs() <= 1e-3 * b[c],
                "{a:?} vs {b:?}"
            );
        }
    }
    assert_no_validation_messages(&ctx);
}

/// Long renders stay exact: a delta sun on a plane has (nearly) zero variance, so the image mean
/// after 16384 samples per pixel must match the closed form to float32 rounding. Adding every
/// sample to the film's float32 running sum read 3.5e-5 low after 4096 samples and 3.2e-4 after
/// 32768 (measured); now the GPU sums at most 256 samples per pixel before the host moves them
/// into float64. On drivers that cap loops (one sample per dispatch, src/render/probe.rs) too.
#[test]
fn film_sums_stay_exact_over_many_samples() {
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    let (case, scene) = load_case("sun-delta", 8, 8);
    let reference = case.reference(&renderer, &scene, 1).unwrap();
    let (expected, _) = mean_luminance(&reference.image, None);
    let settings = RenderSettings {
        spp: 16384,
        trace: trace_mode(),
        ..Default::default()
    };
    let out = renderer.render(&scene, &settings, &mut |_, _| {}).unwrap();
    let (mean, _) = mean_luminance(&out.film.beauty, None);
    let rel = mean / expected - 1.0;
    eprintln!("relative error of the mean at 16384 spp: {rel:.2e}");
    assert!(rel.abs() < 3e-5, "{rel:.3e}");
    assert_no_validation_messages(&ctx);
}

/// The camera ray of image position (u, v) ∈ [0, 1]² (row 0 at the top), as `primary.comp` and
/// the closed forms make it.
fn camera_ray(cam: &illum::scene::Camera, u: f64, v: f64) -> glam::DVec3 {
    let forward = (cam.look_at - cam.position).normalize();
    let right = forward.cross(cam.up).normalize();
    let up = right.cross(forward);
    let tan_half = (cam.fov_y_deg.to_radians() * 0.5).tan();
    let aspect = f64::from(cam.width) / f64::from(cam.height);
    (forward + (2.0 * u - 1.0) * tan_half * aspect * right - (2.0 * v - 1.0) * tan_half * up)
        .normalize()
}

/// Where a camera ray meets the floor (y = 0).
fn floor_hit(o: glam::DVec3, d: glam::DVec3) -> glam::DVec3 {
    assert!(d.y < 0.0, "ray misses the floor");
    let p = o - d * (o.y / d.y);
    assert!(
        p.x.abs() < 20.0 && p.z.abs() < 20.0,
        "ray misses the floor rects: {p}"
    );
    p
}

/// Pixels of the SIZE × SIZE images checked against the float64 reference: on both materials
/// (left D-BRDF, right GGX), in and out of the highlights (75–100 % of their radiance is
/// specular).
const GLOSSY_PIXELS: &[(&str, &[(u32, u32)])] = &[
    ("microfacet-alpha-1", &[(6, 12), (14, 12), (2, 20), (20, 4)]),
    (
        "anisotropic-100",
        &[(6, 16), (14, 16), (3, 18), (0, 15), (16, 22)],
    ),
    ("grazing-glossy", &[(9, 12), (14, 12), (3, 12), (1, 8)]),
];
/// The zoomed image that estimates one pixel: ZOOM × ZOOM pixels of a camera at the same place
/// aimed at the pixel centre's floor point, with a field of view of ZOOM_FOV_DEG. Every pixel
/// then sees the same point to ~1e-6 of the distance, so the ZOOM² pixel means are independent
/// estimates of one value: their spread gives the standard error, never the renderer's own
/// variance estimate. Many pixels and few samples: drivers that cap loops (Mesa 22.3) take one
/// dispatch per sample, so samples per pixel, not pixels, set the run time there (8 × 8 pixels
/// at 1024 spp took 281 s on Mesa 22.3, 32 × 32 at 64 spp takes 24 s).
const ZOOM: u32 = 32;
const ZOOM_FOV_DEG: f64 = 1e-4;
const ZOOM_SPP: u32 = 64;
/// Quadrature of the reference, and the finer one that bounds its error.
const PANELS: usize = 24;

/// The glossy cases against the independent reference: for each pixel of GLOSSY_PIXELS, the
/// mean of the zoomed image's pixel means against the float64 integral at the point (a t-test
/// with ZOOM² − 1 degrees of freedom; Šidák over all the pixels at family-wise 1e-3), with the
/// integral's variation over the zoomed footprint (corners against centre) and its quadrature
/// error (against twice the panels) added to the tolerance as deterministic bounds.
fn glossy_against_reference(name: &str) {
    let pixels = GLOSSY_PIXELS.iter().find(|c| c.0 == name).unwrap().1;
    let (_, scene) = load_case(name, SIZE, SIZE);
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    let tests = GLOSSY_PIXELS.iter().map(|c| c.1.len()).sum::<usize>() as f64;
    let n = ZOOM * ZOOM;
    let t_max = t_for(1.0 - (1.0 - 1e-3f64).powf(1.0 / tests), f64::from(n - 1));
    let cam = scene.camera.position;
    let at = |camera: &illum::scene::Camera, u: f64, v: f64, panels: usize| {
        let p = floor_hit(cam, camera_ray(camera, u, v));
        let brdf = reference::floor_brdf(&scene, p);
        reference::radiance(
            &scene,
            &brdf,
            p,
            (cam - p).normalize(),
            reference::Quadrature { panels },
        )
    };
    let mut failures = Vec::new();
    for (i, &(x, y)) in pixels.iter().enumerate() {
        let s = f64::from(SIZE);
        let p = floor_hit(
            cam,
            camera_ray(
                &scene.camera,
                (f64::from(x) + 0.5) / s,
                (f64::from(y) + 0.5) / s,
            ),
        );
        let mut zoom = scene.clone();
        zoom.camera.look_at = p;
        zoom.camera.fov_y_deg = ZOOM_FOV_DEG;
        zoom.camera.width = ZOOM;
        zoom.camera.height = ZOOM;
        let expected = at(&zoom.camera, 0.5, 0.5, PANELS);
        let quadrature = (at(&zoom.camera, 0.5, 0.5, 2 * PANELS) - expected).abs();
        let footprint = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
            .iter()
            .map(|&(u, v)| (at(&zoom.camera, u, v, PANELS) - expected).abs())
            .fold(0.0, f64::max);
        let settings = RenderSettings {
            spp: ZOOM_SPP,
            seed: 11 + i as u64,
            trace: trace_mode(),
            ..Default::default()
        };
        let out = renderer
            .render(&zoom, &settings, &mut |_, _| {})
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(
            out.stats.non_finite_samples, 0,
            "{name}: non-finite samples"
        );
        let values: Vec<f64> = out
            .film
            .beauty
            .iter()
            .map(|p| p.iter().map(|&c| f64::from(c)).sum::<f64>() / 3.0)
            .collect();
        let mean = values.iter().sum::<f64>() / f64::from(n);
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / f64::from(n - 1);
        let se = (var / f64::from(n)).sqrt();
        let bound = footprint + quadrature + FLOAT_FLOOR * expected;
        let t = (mean - expected) / se;
        eprintln!(
            "{name} pixel ({x}, {y}) at {p:.4}: render {mean:.6e} ± {se:.2e}, reference {expected:.6e} \
             (quadrature ± {quadrature:.1e}, footprint ± {footprint:.1e}), t {t:+.2} (limit {t_max:.2} + bounds)"
        );
        if (mean - expected).abs() > t_max * se + bound {
            failures.push(format!(
                "pixel ({x}, {y}): {mean} vs {expected}, t = {t:.2}"
            ));
        }
    }
    assert_no_validation_messages(&ctx);
    assert!(
        failures.is_empty(),
        "{name} against the float64 reference:\n{}",
        failures.join("\n")
    );
}

#[test]
fn microfacet_alpha_1_against_reference() {
    glossy_against_reference("microfacet-alpha-1");
}

#[test]
fn anisotropic_100_against_reference() {
    glossy_against_reference("anisotropic-100");
}

#[test]
fn grazing_glossy_against_reference() {
    glossy_against_reference("grazing-glossy");
}

/// The reference's quadrature over each kind of light against closed forms: a Lambert surface
/// of albedo 1 under a rect light (Lambert's polygon formula), a sphere light and a sun cone
/// both cut by the horizon (Snyder's formula) and a constant dome (radiance L); and the
/// D-BRDF's directional albedo at α = 1 under the dome against the table of docs/techniques.md,
/// "Reference values".
#[test]
fn glossy_reference_quadrature_matches_closed_forms() {
    use illum::stress::closed_form::{polygon_irradiance, sphere_irradiance};
    let lights = |l: &str| {
        scene(&format!(
            r#"{{"camera": {{"position": [0, 3, 4], "look_at": [0, 0, 0], "fov_y": 40, "resolution": [8, 8]}},
                "materials": {{"m": {{"diffuse": [1, 1, 1]}}}},
                "shapes": {{"floor": {{"rect": {{"center": [0, 0, 0], "normal": [0, 1, 0], "size": [9, 9]}}, "material": "m"}}}},
                "lights": {{"l": {l}}}}}"#
        ))
    };
    let p = glam::DVec3::new(0.3, 0.0, -0.2);
    let v = glam::DVec3::new(0.2, 0.9, 0.3).normalize();
    let n = glam::DVec3::Y;
    let lambert = reference::Brdf {
        diffuse: 1.0,
        lobes: vec![],
        t: glam::DVec3::X,
        b: glam::DVec3::Z,
        n,
    };
    let q = reference::Quadrature { panels: PANELS };
    let pi = std::f64::consts::PI;
    let check = |what: &str, got: f64, want: f64, tol: f64| {
        eprintln!("{what}: quadrature {got:.12e}, closed form {want:.12e}");
        assert!((got / want - 1.0).abs() < tol, "{what}: {got} vs {want}");
    };
    // Rect 1 × 0.5 at height 1, tilted, radiance 3.
    let s = lights(
        r#"{"rect": {"center": [1, 1, 0.5], "normal": [-0.3, -1, 0.2], "size": [1, 0.5]}, "intensity": 3, "shadows": false}"#,
    );
    let illum::scene::LightKind::Rect { center, u, v: ev } = s.lights[0].kind else {
        unreachable!()
    };
    let c0 = center - 0.5 * u - 0.5 * ev;
    let corners = [c0 - p, c0 + u - p, c0 + u + ev - p, c0 + ev - p];
    check(
        "rect",
        reference::radiance(&s, &lambert, p, v, q),
        3.0 * polygon_irradiance(n, &corners) / pi,
        1e-10,
    );
    // Sphere light of radius 0.5 whose centre is 0.2 above the horizon: cut by it.
    let s = lights(
        r#"{"sphere": {"center": [3.3, 0.2, -0.2], "radius": 0.5}, "intensity": 2, "shadows": false}"#,
    );
    let (d, r) = (glam::DVec3::new(3.0, 0.2, 0.0), 0.5f64);
    let want = 2.0 * sphere_irradiance(d.normalize().y, (r / d.length()).powi(2)) / pi;
    check(
        "sphere across the horizon",
        reference::radiance(&s, &lambert, p, v, q),
        want,
        1e-8,
    );
    // A 10° sun 2° above the horizon, irradiance 5 at normal incidence.
    let s = lights(
        r#"{"sun": {"direction": [0, 0.0349207694917477, 1], "angular_diameter": 10}, "intensity": 5}"#,
    );
    let rho = 5f64.to_radians();
    let want = 5.0 / (pi * rho.sin().powi(2))
        * sphere_irradiance(2f64.to_radians().sin(), rho.sin().powi(2))
        / pi;
    check(
        "sun across the horizon",
        reference::radiance(&s, &lambert, p, v, q),
        want,
        1e-8,
    );
    // Constant dome of radiance 0.7: the reflected radiance is 0.7 (albedo 1).
    let s = lights(r#"{"dome": {}, "intensity": 0.7}"#);
    let dome = f64::from(0.7f32);
    check(
        "dome",
        reference::radiance(&s, &lambert, p, v, q),
        dome,
        1e-10,
    );
    // D-BRDF, α = 1, F = 1: the directional albedo is P(n·l > 0) under h ~ D (n·h)
    // (docs/techniques.md, "The D-BRDF"); at normal view that is P(θ_h < 45°) = 1 − exp(−1/α²)
    // exactly; at 45° the table's 0.605 (MC, quadrature within 2e-3).
    for (theta, want, tol) in [(0f64, 1.0 - (-1f64).exp(), 1e-9), (45.0, 0.605, 3e-3)] {
        let dbrdf = reference::Brdf {
            diffuse: 0.0,
            lobes: vec![reference::Lobe {
                ggx: false,
                alpha: (1.0, 1.0),
                fresnel: 1.0,
            }],
            ..lambert.clone()
        };
        let v = glam::DVec3::new(theta.to_radians().sin(), theta.to_radians().cos(), 0.0);
        let got = reference::radiance(&s, &dbrdf, p, v, q) / dome;
        eprintln!("D-BRDF albedo at {theta}°: {got:.9} (expected {want:.9})");
        assert!((got - want).abs() < tol, "D-BRDF albedo at {theta}°: {got}");
    }
}
