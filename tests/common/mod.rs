//! Shared helpers of the integration tests: a validated Vulkan context, and renders of inline
//! scenes. `ILLUM_TEST_TRACE=auto|rayquery|bvh` picks the trace path (CI runs the suite on each),
//! `ILLUM_TEST_DEVICE` the device.
#![allow(dead_code)]

use illum::integrators::Direct;
use illum::render::{Integrator, RenderOutput, RenderSettings, Renderer};
use illum::scene::Scene;
use illum::trace::TraceMode;
use illum::vk::{Context, ContextOptions};
use std::path::Path;

mod stats;
pub use stats::*;

pub fn context() -> Context {
    Context::new(&ContextOptions {
        device: std::env::var("ILLUM_TEST_DEVICE").ok(),
        validation: true,
    })
    .expect("creating a Vulkan context with validation layers")
}

pub fn trace_mode() -> TraceMode {
    std::env::var("ILLUM_TEST_TRACE")
        .ok()
        .map(|s| s.parse().expect("ILLUM_TEST_TRACE"))
        .unwrap_or(TraceMode::Auto)
}

/// Fails the test if the validation layers said anything.
pub fn assert_no_validation_messages(ctx: &Context) {
    assert!(ctx.validation_enabled(), "validation layers are not on");
    let m = ctx.validation_messages();
    assert!(
        m.is_empty(),
        "{} validation message(s):\n{}",
        m.len(),
        m.join("\n")
    );
}

pub fn scene(json: &str) -> Scene {
    illum::scene::from_json_str(json, "<test scene>", Path::new("."))
        .unwrap_or_else(|e| panic!("test scene: {e}"))
}

pub fn render_with(ctx: &Context, scene: &Scene, spp: u32, seed: u64) -> RenderOutput {
    let settings = RenderSettings {
        spp,
        seed,
        trace: trace_mode(),
        ..Default::default()
    };
    Renderer::new(ctx.clone())
        .render(scene, &settings, &mut |_, _| {})
        .unwrap_or_else(|e| panic!("render failed: {e}"))
}

/// One render per seed with the same renderer (its kernels compiled once).
pub fn render_seeds(
    renderer: &Renderer,
    scene: &Scene,
    s: &RenderSettings,
    seeds: &[u64],
) -> Vec<RenderOutput> {
    renderer
        .render_seeds(scene, s, seeds, &mut |_, _| {})
        .unwrap_or_else(|e| panic!("render failed: {e}"))
}

/// Every pixel of every render exactly black, and shadow rays traced (more than two per pixel of
/// a `w` x `h` image): a fully shadowed scene.
pub fn assert_shadowed_black(outs: &[RenderOutput], w: u32, h: u32, name: &str) {
    for o in outs {
        for p in &o.film.beauty {
            assert_eq!(*p, [0.0; 3], "{name}: a shadowed pixel is lit");
        }
        assert!(
            o.stats.rays > u64::from(w * h * 2),
            "{name}: shadow rays were traced"
        );
    }
}

/// Renders on a fresh validated context and checks that validation stayed silent.
pub fn render(json: &str, spp: u32) -> RenderOutput {
    let ctx = context();
    let out = render_with(&ctx, &scene(json), spp, 0);
    assert_no_validation_messages(&ctx);
    out
}

/// A unique path in the temporary directory.
pub fn temp_path(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("illum-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

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

/// Welch's degrees of freedom of a sum of independent variance estimates (v_i, dof_i).
pub fn welch_dof(parts: &[(f64, f64)]) -> f64 {
    let total: f64 = parts.iter().map(|p| p.0).sum();
    let denom: f64 = parts.iter().map(|p| p.0 * p.0 / p.1).sum();
    if denom > 0.0 {
        total * total / denom
    } else {
        f64::INFINITY
    }
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

/// A small scene for the render-core tests (jobs, farm, prepared scenes): a glossy floor, a
/// diffuse ball, a rect light and a dome, at 13x9 pixels (odd sizes on purpose).
pub const SMALL_SCENE: &str = r#"{"camera": {"position": [0, 1.2, 3], "look_at": [0, 0.3, 0], "fov_y": 40, "resolution": [13, 9]},
    "materials": {"floor": {"diffuse": [0.6, 0.6, 0.6], "specular": [{"model": "ggx", "roughness": 0.2}]},
                  "ball": {"diffuse": [0.7, 0.3, 0.2]}},
    "shapes": {"floor": {"rect": {"center": [0, 0, 0], "normal": [0, 1, 0], "size": [6, 6]}, "material": "floor"},
               "ball": {"sphere": {"center": [0, 0.5, 0], "radius": 0.5}, "material": "ball"}},
    "lights": {"key": {"rect": {"center": [1, 2, 1], "normal": [-0.4, -1, -0.4], "size": [0.8, 0.8]}, "intensity": 6},
               "sky": {"dome": {}, "color": [0.2, 0.3, 0.4]}}}"#;

/// The illum binary, with validation on.
pub fn illum_command() -> std::process::Command {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_illum"));
    c.env("ILLUM_VALIDATION", "1");
    c
}

/// Runs the illum binary with validation on: (exit code, stderr).
pub fn illum_cli(args: &[&str]) -> (i32, String) {
    let out = illum_command().args(args).output().expect("running illum");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Rec. 709 luminance of a pixel.
pub fn luminance(p: [f32; 3]) -> f64 {
    0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
}

/// Independent renders (one per seed) summarised per `block` x `block` pixel block (whole
/// blocks only), followed by the whole image: for each, the mean luminance over the seeds and
/// the variance of that mean from the seeds' scatter.
pub fn block_stats(outs: &[RenderOutput], block: u32) -> Vec<(f64, f64)> {
    let per: Vec<Vec<f64>> = outs
        .iter()
        .map(|o| {
            let f = &o.film;
            let (bx, by) = (f.width / block, f.height / block);
            let mut v = vec![0.0; (bx * by) as usize + 1];
            for y in 0..f.height {
                for x in 0..f.width {
                    let l = luminance(f.beauty[(y * f.width + x) as usize]);
                    if x < bx * block && y < by * block {
                        v[((y / block) * bx + x / block) as usize] += l / f64::from(block * block);
                    }
                    v[(bx * by) as usize] += l / f64::from(f.width * f.height);
                }
            }
            v
        })
        .collect();
    let k = per.len() as f64;
    (0..per[0].len())
        .map(|b| {
            let m = per.iter().map(|p| p[b]).sum::<f64>() / k;
            let var = per.iter().map(|p| (p[b] - m).powi(2)).sum::<f64>() / (k - 1.0);
            (m, var / k)
        })
        .collect()
}

/// The floor points (y = 0) seen through each pixel of a w × h camera at `pos` looking at the
/// origin (vertical field of view `fov_deg`, up +Y), on a 4 × 4 grid of sub-pixel positions.
pub fn floor_points(pos: glam::DVec3, fov_deg: f64, w: u32, h: u32) -> Vec<Vec<glam::DVec3>> {
    let f = (-pos).normalize();
    let r = f.cross(glam::DVec3::Y).normalize();
    let u = r.cross(f);
    let t = (fov_deg.to_radians() / 2.0).tan();
    let mut out = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let mut pts = Vec::new();
            for j in 0..4 {
                for i in 0..4 {
                    let nx = 2.0 * (f64::from(x) + (f64::from(i) + 0.5) / 4.0) / f64::from(w) - 1.0;
                    let ny = 2.0 * (f64::from(y) + (f64::from(j) + 0.5) / 4.0) / f64::from(h) - 1.0;
                    let d = (f + nx * r * t - ny * u * t).normalize();
                    pts.push(pos + d * (-pos.y / d.y));
                }
            }
            out.push(pts);
        }
    }
    out
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
