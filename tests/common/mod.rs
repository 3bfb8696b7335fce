//! Shared helpers of the integration tests: a validated Vulkan context, and renders of inline
//! scenes. `ILLUM_TEST_TRACE=auto|rayquery|bvh` picks the trace path (CI runs the suite on each),
//! `ILLUM_TEST_DEVICE` the device.
#![allow(dead_code)]

use illum::render::{RenderOutput, RenderSettings, Renderer};
use illum::scene::Scene;
use illum::trace::TraceMode;
use illum::vk::{Context, ContextOptions};
use std::path::Path;

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
    assert!(m.is_empty(), "{} validation message(s):\n{}", m.len(), m.join("\n"));
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
