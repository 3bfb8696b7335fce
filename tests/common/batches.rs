//! Independent batches of renders and per-pixel t-tests of their means against an expectation.

use super::{assert_no_validation_messages, context, scene, t_for, trace_mode, welch_dof};
use illum::integrators::Direct;
use illum::render::{Integrator, RenderSettings, Renderer};
use illum::scene::Scene;

/// Independent renders per image in the statistical tests: the variance of each pixel mean is
/// estimated from their spread (BATCHES − 1 degrees of freedom), never taken from the
/// renderer's own Variance AOV, which a renderer could over-report and pass every test.
pub const BATCHES: u32 = 16;

/// `k` renders of one scene with independent seeds, `spp / k` samples each, on one renderer.
pub struct Batches {
    pub k: u32,
    /// Per pixel and channel: the mean of the k render means.
    pub mean: Vec<[f64; 3]>,
    /// Per pixel and channel: the variance of `mean`, estimated from the spread of the k means
    /// (sample variance / k).
    pub var: Vec<[f64; 3]>,
    pub non_finite_samples: u64,
}

impl Batches {
    /// Renders `settings.spp` samples per pixel in `k` independent renders (seeds
    /// `settings.seed · 64 + j`) with one pipeline (`Renderer::render_seeds`).
    pub fn render(
        renderer: &Renderer,
        scene: &Scene,
        settings: &RenderSettings,
        k: u32,
    ) -> Batches {
        assert!(
            (2..=64).contains(&k) && settings.spp % k == 0,
            "{} spp in {k} batches",
            settings.spp
        );
        let seeds: Vec<u64> = (0..u64::from(k)).map(|j| settings.seed * 64 + j).collect();
        let s = RenderSettings {
            spp: settings.spp / k,
            ..settings.clone()
        };
        let outs = renderer
            .render_seeds(scene, &s, &seeds, &mut |_, _| {})
            .unwrap_or_else(|e| panic!("render failed: {e}"));
        let mut sum: Vec<[f64; 3]> = vec![[0.0; 3]; outs[0].film.beauty.len()];
        let mut sum2 = sum.clone();
        let mut non_finite_samples = 0;
        for out in &outs {
            non_finite_samples += out.stats.non_finite_samples;
            for (i, p) in out.film.beauty.iter().enumerate() {
                for c in 0..3 {
                    let x = f64::from(p[c]);
                    sum[i][c] += x;
                    sum2[i][c] += x * x;
                }
            }
        }
        let kf = f64::from(k);
        let mean: Vec<[f64; 3]> = sum.iter().map(|s| s.map(|x| x / kf)).collect();
        let var = sum2
            .iter()
            .zip(&mean)
            .map(|(s2, m)| {
                let mut v = [0.0; 3];
                for c in 0..3 {
                    v[c] = ((s2[c] - kf * m[c] * m[c]) / (kf - 1.0)).max(0.0) / kf;
                }
                v
            })
            .collect();
        Batches {
            k,
            mean,
            var,
            non_finite_samples,
        }
    }
}

/// Renders `spp` samples per pixel of `json` in BATCHES independent renders on a fresh validated
/// context, and checks that validation stayed silent.
pub fn render_batches(json: &str, spp: u32, seed: u64) -> Batches {
    render_batches_with(&scene(json), Direct::default(), spp, seed)
}

/// The same for a loaded scene and integrator settings.
pub fn render_batches_with(
    scene: &Scene,
    integrator: impl Into<std::sync::Arc<dyn Integrator>>,
    spp: u32,
    seed: u64,
) -> Batches {
    let ctx = context();
    let settings = RenderSettings {
        spp,
        seed,
        trace: trace_mode(),
        integrator: integrator.into(),
        ..Default::default()
    };
    let b = Batches::render(&Renderer::new(ctx.clone()), scene, &settings, BATCHES);
    assert_no_validation_messages(&ctx);
    b
}

/// Checks `k` independent renders against the per-pixel expectation `expected(i)` (RGB) with a
/// t-test per pixel and channel (k − 1 degrees of freedom, variance from the renders' spread), at
/// family-wise significance `alpha` (Šidák over all tests); and the image mean per channel at
/// the same level (Welch's dof). Pixels whose renders all agree must match to float rounding.
pub fn assert_matches_expectation(b: &Batches, expected: impl Fn(usize) -> [f64; 3], alpha: f64) {
    let tests = (b.mean.len() * 3) as f64;
    let per = 1.0 - (1.0 - alpha).powf(1.0 / tests);
    let dof = f64::from(b.k - 1);
    let t = t_for(per, dof);
    let (mut sum_d, mut parts) = ([0.0f64; 3], [vec![], vec![], vec![]]);
    let mut worst = 0.0f64;
    for (i, (m, v)) in b.mean.iter().zip(&b.var).enumerate() {
        let e = expected(i);
        for c in 0..3 {
            let d = m[c] - e[c];
            let floor = 1e-5 * e[c].abs() + 1e-6;
            let tol = t * v[c].sqrt() + floor;
            worst = worst.max((d.abs() - floor).max(0.0) / v[c].sqrt().max(1e-300));
            assert!(
                d.abs() <= tol,
                "pixel {i} channel {c}: {} vs expected {} (± {tol}, t = {:.2}, limit {t:.2})",
                m[c],
                e[c],
                d / v[c].sqrt()
            );
            sum_d[c] += d;
            parts[c].push((v[c], dof));
        }
    }
    eprintln!(
        "largest |t| over pixels: {worst:.2} (limit {t:.2}, {} dof)",
        b.k - 1
    );
    let n = b.mean.len() as f64;
    for c in 0..3 {
        let var: f64 = parts[c].iter().map(|p| p.0).sum();
        let tm = t_for(alpha / 3.0, welch_dof(&parts[c]));
        let tol = tm * var.sqrt() / n + 1e-6;
        eprintln!(
            "image mean channel {c}: t = {:.2} (limit {tm:.2})",
            sum_d[c] / var.sqrt().max(1e-300)
        );
        assert!(
            (sum_d[c] / n).abs() <= tol,
            "channel {c}: image mean off by {} (± {tol})",
            sum_d[c] / n
        );
    }
}

/// Checks renders of a Lambert floor of `albedo` against its radiance albedo E / pi, with the
/// irradiance E(x) averaged over each pixel's floor points `pts` (floor_points), at family-wise
/// significance 0.01 (assert_matches_expectation).
pub fn assert_lambert_floor(
    b: &Batches,
    pts: &[Vec<glam::DVec3>],
    albedo: f64,
    irradiance: impl Fn(glam::DVec3) -> f64,
) {
    assert_matches_expectation(
        b,
        |i| {
            let e = pts[i].iter().map(|&p| irradiance(p)).sum::<f64>() / pts[i].len() as f64;
            [albedo * e / std::f64::consts::PI; 3]
        },
        0.01,
    );
}
