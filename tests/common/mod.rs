//! Shared helpers of the integration tests: a validated Vulkan context, and renders of inline
//! scenes. `ILLUM_TEST_TRACE=auto|rayquery|bvh` picks the trace path (CI runs the suite on each),
//! `ILLUM_TEST_DEVICE` the device.
#![allow(dead_code)]

use illum::render::{RenderOutput, RenderSettings, Renderer};
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

/// Checks a rendered film of `spp` samples against the per-pixel expectation `expected(i)` (RGB)
/// with a t-test per pixel and channel, using the Variance AOV, at family-wise significance
/// `alpha` (Šidák over all tests); and the image mean at the same level. Pixels with zero
/// variance must match to float rounding.
pub fn assert_matches_expectation(
    film: &illum::output::Film,
    spp: u32,
    expected: impl Fn(usize) -> [f64; 3],
    alpha: f64,
) {
    let var = film.variance.as_ref().expect("variance AOV");
    let tests = (film.beauty.len() * 3) as f64;
    let per = 1.0 - (1.0 - alpha).powf(1.0 / tests);
    let z = t_for(per, f64::from(spp.max(2) - 1));
    let (mut sum_d, mut sum_v) = ([0.0f64; 3], [0.0f64; 3]);
    for (i, p) in film.beauty.iter().enumerate() {
        let e = expected(i);
        for c in 0..3 {
            let d = f64::from(p[c]) - e[c];
            let v = f64::from(var[i][c]);
            let tol = z * v.sqrt() + 1e-5 * e[c].abs() + 1e-6;
            assert!(
                d.abs() <= tol,
                "pixel {i} channel {c}: {} vs expected {} (± {tol})",
                p[c],
                e[c]
            );
            sum_d[c] += d;
            sum_v[c] += v;
        }
    }
    let n = film.beauty.len() as f64;
    let zm = z_for(alpha / 3.0);
    for c in 0..3 {
        let tol = zm * sum_v[c].sqrt() / n + 1e-6;
        assert!(
            (sum_d[c] / n).abs() <= tol,
            "channel {c}: image mean off by {} (± {tol})",
            sum_d[c] / n
        );
    }
}
