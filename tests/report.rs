//! Error against run time: the half-buffer estimate tracks the true error on a scene with a
//! closed-form answer, reports have one row per pass, and budgets are honoured.

mod common;
use common::*;
use illum::render::{RenderSettings, Renderer};

/// A Lambert plane (albedo 0.5) under a sun of 30° angular diameter, 45° from the normal, with
/// E⊥ = 3: the cone is entirely above the horizon, so the irradiance is exactly E⊥ cos 45° at
/// every point and the outgoing radiance is 0.5/π · 3 · cos 45° everywhere.
const SUN_PLANE: &str = r#"{
    "camera": {"position": [0, 1, 0], "look_at": [0, 0, -1], "fov_y": 40, "resolution": [64, 64]},
    "materials": {"m": {"diffuse": [0.5, 0.5, 0.5]}},
    "shapes": {"floor": {"disk": {"center": [0, 0, -1], "normal": [0, 1, 0], "radius": 1000}, "material": "m"}},
    "lights": {"sun": {"sun": {"direction": [1, 1, 0], "angular_diameter": 30}, "intensity": 3}}}"#;

fn sun_plane_answer() -> f32 {
    (0.5 / std::f64::consts::PI * 3.0 * std::f64::consts::FRAC_1_SQRT_2) as f32
}

#[test]
fn half_buffer_estimate_agrees_with_the_true_error_across_passes() {
    let ctx = context();
    let s = scene(SUN_PLANE);
    let reference = vec![[sun_plane_answer(); 3]; 64 * 64];
    let settings = RenderSettings {
        spp: 24,
        seed: 1,
        trace: trace_mode(),
        reference: Some(reference),
        ..Default::default()
    };
    let out = Renderer::new(ctx.clone())
        .render(&s, &settings, &mut |_, _| {})
        .unwrap();
    assert_no_validation_messages(&ctx);
    // The image mean converges to the closed form (unbiased estimator): z-test on the mean.
    let n = out.film.beauty.len() as f64;
    let mean = out.film.beauty.iter().map(|p| f64::from(p[0])).sum::<f64>() / n;
    let var_mean = out
        .film
        .variance
        .as_ref()
        .unwrap()
        .iter()
        .map(|v| f64::from(v[0]))
        .sum::<f64>()
        / n
        / n;
    let answer = f64::from(sun_plane_answer());
    assert!(
        (mean - answer).abs() < 4.0 * var_mean.sqrt() + 1e-6,
        "mean {mean}, expected {answer} ± {}",
        4.0 * var_mean.sqrt()
    );
    let mut checked = 0;
    for p in &out.passes {
        let (Some(est), Some(err)) = (p.estimated_relmse, p.error) else {
            assert_eq!(p.spp, 1, "only the 1-sample pass lacks an estimate");
            continue;
        };
        // Each of the two is a mean over 4096 pixels of a scaled χ²(1) (grey: the channels
        // agree), relative spread sqrt(2/4096) = 2.2%; their difference is within 5 standard
        // deviations, plus the known bias of the image-based denominator, ≤ 3 Var(pixel)/pixel²
        // (measured here from the relMSE itself).
        let sd = (2.0f64 / 4096.0).sqrt() * 2f64.sqrt();
        let bias = 3.0 * err.relmse;
        let ratio = est / err.relmse;
        assert!(
            (ratio - 1.0).abs() < 5.0 * sd + bias,
            "pass {} ({} spp): estimated relMSE {est}, true {}",
            p.pass,
            p.spp,
            err.relmse
        );
        assert_eq!(err.non_finite_pixels, 0);
        checked += 1;
    }
    assert!(checked >= 5, "only {checked} passes");
    // The true error falls like 1/spp for an unbiased estimator.
    let first = out
        .passes
        .iter()
        .find(|p| p.spp == 2)
        .unwrap()
        .error
        .unwrap()
        .relmse;
    let last = out.passes.last().unwrap().error.unwrap().relmse;
    assert!(
        last < first / 6.0,
        "relMSE {first} at 2 spp, {last} at 24 spp"
    );
}

#[test]
fn report_has_one_row_per_pass_with_time_non_decreasing() {
    let ctx = context();
    let settings = RenderSettings {
        spp: 40,
        trace: trace_mode(),
        evaluate_passes: true,
        ..Default::default()
    };
    let out = Renderer::new(ctx.clone())
        .render(&scene(SUN_PLANE), &settings, &mut |_, _| {})
        .unwrap();
    assert_no_validation_messages(&ctx);
    assert!(out.passes.len() > 4);
    for (i, w) in out.passes.windows(2).enumerate() {
        assert_eq!(w[0].pass as usize, i);
        assert!(w[1].spp > w[0].spp);
        assert!(w[1].wall_seconds >= w[0].wall_seconds);
        assert!(w[1].device_seconds >= w[0].device_seconds);
    }
    assert_eq!(out.passes.last().unwrap().spp, 40);
    assert_eq!(out.stats.spp, 40);
    assert!(out.passes.iter().all(|p| p.error.is_none()));

    let csv = temp_path("report.csv");
    illum::report::write_csv(&csv, &out.passes).unwrap();
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert!(
        lines[0]
            .starts_with("pass,spp,device_seconds,wall_seconds,rmse,relmse,mae,estimated_relmse")
    );
    assert_eq!(lines.len(), out.passes.len() + 1);
}

#[test]
fn time_budget_stops_within_one_pass() {
    let ctx = context();
    let budget = 0.6;
    let settings = RenderSettings {
        spp: 1 << 20,
        time: Some(budget),
        trace: trace_mode(),
        evaluate_passes: true,
        ..Default::default()
    };
    let out = Renderer::new(ctx.clone())
        .render(&scene(SUN_PLANE), &settings, &mut |_, _| {})
        .unwrap();
    assert_no_validation_messages(&ctx);
    let n = out.passes.len();
    assert!(n >= 2);
    // Every pass but the last started before the budget ran out; the last ended at or after it
    // (or the cap was hit).
    assert!(out.passes[n - 2].wall_seconds < budget);
    assert!(out.passes[n - 1].wall_seconds >= budget || out.stats.spp == 1 << 20);
}
