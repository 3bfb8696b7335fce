//! The bias of the course's average-visibility control variate (`--control-variates avgvis`,
//! docs/techniques.md, "Control variates"): with N i.i.d. light samples,
//! E[I_cv] − I = −Cov(V_i, g_i) / N.
//!
//! The scene is 1-D-like and computed independently on the host: a floor point p = (1, 0, 0)
//! (albedo ρ) under an 8 × 8 rect light of radiance L at height 1 (sampled uniformly in solid angle,
//! N samples: its share of the hemisphere is above 1), half hidden by an opaque sheet at height 1/2
//! whose edge is the line x = 0: a light point X is visible iff (1 + X_x) / 2 > 0. With g the
//! diffuse term in units of ρL/π, g_i = Ω cos_i, the moments are integrals over the rect:
//! E[g] = ∫ cos dω, E[V] = Ω_vis / Ω, E[V g] = ∫_vis cos dω (f64 midpoint rule, the edge on a grid
//! line). The camera looks straight down at p with a 0.01° field of view (every pixel sees p to
//! within 3e-5), so every camera sample is an independent draw of the same estimator.
//! At N = 4 and N = 16 the measured bias (pixel mean − ρL/π E[V g]) must match −Cov/N within
//! the pixels' standard error (normal quantile, Šidák over the two at level 1e-3), and the
//! prediction must be ≥ 2 quantiles from 0, so an unbiased form (`loo`, or visibility from another
//! sample set) fails the comparison.

mod common;
use common::*;
use illum::integrators::{ControlVariates, Direct, DirectLighting, Technique};
use illum::render::{RenderSettings, Renderer};

const ALBEDO: f64 = 0.5;
const RADIANCE: f64 = 2.0;

/// (E[g], E[V], E[V g]) of g = Ω cos at p = (1, 0, 0), in units of ρL/π.
fn moments() -> (f64, f64, f64) {
    let n = 2400; // cells per side: the visible part X > -1 starts on a grid line
    let h = 8.0 / n as f64;
    let (mut om, mut om_vis, mut e, mut e_vis) = (0.0, 0.0, 0.0, 0.0);
    for i in 0..n {
        let x = -4.0 + (i as f64 + 0.5) * h;
        let visible = x > -1.0;
        for j in 0..n {
            let z = -4.0 + (j as f64 + 0.5) * h;
            let d2 = (x - 1.0) * (x - 1.0) + z * z + 1.0;
            let dw = h * h / (d2 * d2.sqrt()); // cos_light dA / d^2, cos_light = 1 / d
            let cos = 1.0 / d2.sqrt();
            om += dw;
            e += dw * cos;
            if visible {
                om_vis += dw;
                e_vis += dw * cos;
            }
        }
    }
    (e, om_vis / om, e_vis)
}

#[test]
fn average_visibility_bias_is_minus_cov_over_n() {
    let (eg, ev, evg) = moments();
    let cov = evg - ev * eg;
    let scale = ALBEDO * RADIANCE / std::f64::consts::PI;
    let truth = scale * evg;
    let json = format!(
        r#"{{"camera": {{"position": [1, 0.3, 0], "look_at": [1, 0, 0], "up": [0, 0, 1], "fov_y": 0.01, "resolution": [32, 32]}},
        "materials": {{"m": {{"diffuse": [{ALBEDO}, {ALBEDO}, {ALBEDO}]}}}},
        "shapes": {{"floor": {{"rect": {{"center": [0, 0, 0], "normal": [0, 1, 0], "size": [40, 40]}}, "material": "m"}},
                   "sheet": {{"rect": {{"center": [-10, 0.5, 0], "normal": [0, -1, 0], "size": [20, 40]}}, "material": "m"}}}},
        "lights": {{"key": {{"rect": {{"center": [0, 1, 0], "normal": [0, -1, 0], "size": [8, 8]}}, "color": [{RADIANCE}, {RADIANCE}, {RADIANCE}]}}}}}}"#
    );
    let scene = scene(&json);
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    let z = t_for(1.0 - (1.0 - 1e-3f64).powf(0.5), f64::INFINITY);
    for n in [4u32, 16] {
        let s = RenderSettings {
            spp: 4,
            trace: trace_mode(),
            integrator: Direct(DirectLighting {
                technique: Technique::Mis,
                light_samples: n,
                control_variates: ControlVariates::AvgVis,
                ..Default::default()
            })
            .into(),
            ..Default::default()
        };
        let outs = render_seeds(&renderer, &scene, &s, &[11, 12, 13, 14]);
        let xs: Vec<f64> = outs
            .iter()
            .flat_map(|o| o.film.beauty.iter().map(|p| luminance(*p)))
            .collect();
        let k = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / k;
        let se = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (k - 1.0) / k).sqrt();
        let predicted = -scale * cov / f64::from(n);
        let measured = mean - truth;
        eprintln!(
            "N = {n}: bias {measured:.5} ± {se:.5}, predicted -Cov/N = {predicted:.5} (truth {truth:.5})"
        );
        assert!(
            predicted.abs() >= 2.0 * z * se,
            "N = {n}: the predicted bias {predicted} is too small to test against {se}"
        );
        assert!(
            (measured - predicted).abs() <= z * se,
            "N = {n}: avgvis bias {measured} ± {se} vs predicted -Cov/N = {predicted} ({:.2} se, limit {z:.2})",
            (measured - predicted) / se
        );
    }
    assert_no_validation_messages(&ctx);
}
