//! Fewer shadow rays (glsl/direct/shadow.glsl; docs/techniques.md, "Shadow resampling" and
//! "Shadow culling"): resampled shadow rays (`shadow_resample`) and Russian roulette on each candidate
//! (`shadow_cull`) against the plain estimator, on a floor in the penumbra of a sphere under a
//! large rect light.
//!
//! * Unbiased: block means (4x4 pixels, luminance) and the image mean of SEEDS independent renders
//!   per estimator (Renderer::render_prepared with distinct seeds), Welch t-tests with the
//!   variances from the scatter of those renders, Šidák over the blocks.
//! * Rays: under light sampling alone every camera sample takes exactly LIGHT_SAMPLES non-zero
//!   candidates (the light covers more than the hemisphere's share, so the count is the most),
//!   so the plain estimator traces exactly that many shadow rays; resampling with pct traces at
//!   most ceil(pct LIGHT_SAMPLES); culling with a threshold above every candidate's luminance
//!   traces, in expectation, sum_i luminance(c_i) / T, which the plain render's unshadowed sum predicts.

mod common;
use common::*;
use illum::integrators::{Direct, DirectLighting, Technique};
use illum::render::{RenderOutput, RenderSettings, Renderer};

const W: u32 = 24;
const H: u32 = 16;
const SEEDS: u64 = 16;
const LIGHT_SAMPLES: u32 = 8;
/// The light's radiance and the floor's albedo (grey, so luminance = each channel).
const RADIANCE: f64 = 2.0;
const ALBEDO: f64 = 0.5;

/// The camera looks straight down at the floor from below the light; the occluder sits above
/// the camera, out of its view, and shades part of the light from every pixel (a penumbra). The
/// floor is diffuse plus a glossy lobe, so that MIS also takes BRDF samples.
fn scene_json(occluder: bool) -> String {
    let sphere = if occluder {
        r#", "ball": {"sphere": {"center": [0.35, 0.5, 0], "radius": 0.25}, "material": "m"}"#
    } else {
        ""
    };
    format!(
        r#"{{"camera": {{"position": [0, 0.3, 0], "look_at": [0, 0, 0], "up": [0, 0, 1], "fov_y": 60, "resolution": [{W}, {H}]}},
        "materials": {{"m": {{"diffuse": [{ALBEDO}, {ALBEDO}, {ALBEDO}], "specular": [{{"model": "ggx", "roughness": 0.3}}]}}}},
        "shapes": {{"floor": {{"rect": {{"center": [0, 0, 0], "normal": [0, 1, 0], "size": [40, 40]}}, "material": "m"}}{sphere}}},
        "lights": {{"key": {{"rect": {{"center": [0, 1, 0], "normal": [0, -1, 0], "size": [8, 8]}}, "color": [{RADIANCE}, {RADIANCE}, {RADIANCE}], "intensity": 1}}}}}}"#
    )
}

fn settings(technique: Technique, spp: u32, resample: f32, cull: f32) -> RenderSettings {
    RenderSettings {
        spp,
        trace: trace_mode(),
        integrator: Direct(DirectLighting {
            technique,
            light_samples: LIGHT_SAMPLES,
            shadow_resample: resample,
            shadow_cull: cull,
            ..Default::default()
        })
        .into(),
        ..Default::default()
    }
}

/// Mean and variance of the mean over the seeds, per 4x4 block, then for the whole image.
fn stats(outs: &[RenderOutput]) -> Vec<(f64, f64)> {
    block_stats(outs, 4)
}

fn shadow_rays(outs: &[RenderOutput], spp: u32) -> u64 {
    let camera = u64::from(W * H * spp) * outs.len() as u64;
    outs.iter().map(|o| o.stats.rays).sum::<u64>() - camera
}

#[test]
fn resampling_and_culling_are_unbiased_and_trace_fewer_rays() {
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    let scene = scene(&scene_json(true));
    let prepared = renderer.prepare(&scene, trace_mode()).expect("prepare");
    let seeds = |base: u64| (0..SEEDS).map(|j| base * 64 + j).collect::<Vec<_>>();
    let render = |s: &RenderSettings, base: u64| {
        renderer
            .render_prepared(&prepared, &scene.camera, s, &seeds(base), &mut |_, _| {})
            .unwrap_or_else(|e| panic!("render failed: {e}"))
    };

    // The culling threshold: above every candidate's luminance. The rect is solid-angle sampled
    // (it covers most of the hemisphere), so a light sample carries at most
    // (rho/pi + glossy f cos) L 2 pi / LIGHT_SAMPLES: rho/pi = 0.16, and GGX's peak f cos (alpha
    // 0.09, f0 0.04) is about 0.4, so at most about 0.9, below 3 rho L = 3.
    let threshold = (3.0 * ALBEDO * RADIANCE) as f32;
    let spp = 4;

    // Unbiased, under MIS (light and BRDF sample groups).
    let plain = render(&settings(Technique::Mis, spp, 1.0, 0.0), 1);
    let plain_s = stats(&plain);
    let lit = plain_s.iter().filter(|(m, _)| *m > 0.0).count();
    assert_eq!(lit, plain_s.len(), "every block must be lit");
    let spread = plain_s[..plain_s.len() - 1]
        .iter()
        .map(|(m, _)| *m)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), m| {
            (lo.min(m), hi.max(m))
        });
    assert!(
        spread.1 > 1.05 * spread.0,
        "the occluder must shade the image unevenly (a penumbra): blocks {spread:?}"
    );
    let mut rays = vec![("plain", shadow_rays(&plain, spp))];
    for (name, resample, cull) in [("resample 0.5", 0.5, 0.0), ("cull", 1.0, threshold / 4.0)] {
        let outs = render(&settings(Technique::Mis, spp, resample, cull), 2);
        assert!(outs.iter().all(|o| o.stats.non_finite_samples == 0));
        rays.push((name, shadow_rays(&outs, spp)));
        let s = stats(&outs);
        let blocks = s.len() as f64;
        let per = 1.0 - (1.0 - 1e-3f64).powf(1.0 / blocks);
        let dof = (SEEDS - 1) as f64;
        for (b, (&(m1, v1), &(m0, v0))) in s.iter().zip(&plain_s).enumerate() {
            let t = t_for(per, welch_dof(&[(v1, dof), (v0, dof)]));
            let se = (v1 + v0).sqrt();
            eprintln!(
                "{name}: block {b}: {m1:.5} vs plain {m0:.5} (t = {:.2}, limit {t:.2}, se {:.2}%)",
                (m1 - m0) / se,
                100.0 * se / m0
            );
            assert!(
                (m1 - m0).abs() <= t * se,
                "{name}: block {b}: {m1} vs plain {m0} (t = {:.2}, limit {t:.2})",
                (m1 - m0) / se
            );
        }
    }
    eprintln!("shadow rays under MIS, {spp} spp x {SEEDS} seeds: {rays:?}");
    assert!(rays[1].1 < rays[0].1 && rays[2].1 < rays[0].1);

    // Ray counts, under light sampling alone.
    let spp = 16;
    let samples = u64::from(W * H * spp) * SEEDS;
    let plain = render(&settings(Technique::Light, spp, 1.0, 0.0), 3);
    assert_eq!(
        shadow_rays(&plain, spp),
        samples * u64::from(LIGHT_SAMPLES),
        "plain: one shadow ray per light sample"
    );
    let half = render(&settings(Technique::Light, spp, 0.5, 0.0), 4);
    let r = shadow_rays(&half, spp);
    eprintln!(
        "resample 0.5: {:.3} shadow rays per camera sample (plain {LIGHT_SAMPLES})",
        r as f64 / samples as f64
    );
    assert!(
        r <= samples * u64::from(LIGHT_SAMPLES.div_ceil(2)) && r >= samples,
        "resample 0.5: {r} shadow rays for {samples} camera samples"
    );

    // Culling: E[rays] = sum_i luminance(c_i) / T with every luminance(c_i) <= T. The unshadowed sum is the
    // occluder-free scene's image (same kernels: the same features).
    let open = self::scene(&scene_json(false));
    let open_prepared = renderer.prepare(&open, trace_mode()).expect("prepare");
    let render_open = |s: &RenderSettings, base: u64| {
        renderer
            .render_prepared(
                &open_prepared,
                &open.camera,
                s,
                &seeds(base),
                &mut |_, _| {},
            )
            .unwrap_or_else(|e| panic!("render failed: {e}"))
    };
    let unshadowed = render_open(&settings(Technique::Light, spp, 1.0, 0.0), 7);
    // Sum over every camera sample of sum_i luminance(c_i), and its standard error over the seeds.
    let totals: Vec<f64> = unshadowed
        .iter()
        .map(|o| o.film.beauty.iter().map(|p| luminance(*p)).sum::<f64>() * f64::from(spp))
        .collect();
    let k = totals.len() as f64;
    let total = totals.iter().sum::<f64>();
    let mean = total / k;
    let var_total = k * totals.iter().map(|t| (t - mean).powi(2)).sum::<f64>() / (k - 1.0);
    let expected = total / f64::from(threshold);
    let culled = render(&settings(Technique::Light, spp, 1.0, threshold), 8);
    let got = shadow_rays(&culled, spp) as f64;
    // Binomial count (variance at most its mean) plus the estimate's own error.
    let se = (expected + var_total / f64::from(threshold).powi(2)).sqrt();
    eprintln!(
        "cull at {threshold}: {got} shadow rays, expected {expected:.1} ± {se:.1} (plain {})",
        samples * u64::from(LIGHT_SAMPLES)
    );
    assert!(
        (got - expected).abs() <= 4.0 * se,
        "cull: {got} shadow rays, expected {expected:.1} ± {se:.1}"
    );
    assert!(got < 0.5 * (samples * u64::from(LIGHT_SAMPLES)) as f64);
    assert_no_validation_messages(&ctx);
}
