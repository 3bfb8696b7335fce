//! The denoiser (Open Image Denoise through src/denoise.rs): on three scenes a 16-spp render's
//! relMSE against a 256-spp reference (its own noise a sixteenth of the image's) falls when denoised, and the denoised image keeps the
//! beauty's mean within 1% per channel; `illum render --denoise` adds the layer and leaves every
//! other plane bit for bit as rendered; a missing library is a clear error before any render.

mod common;
use common::*;
use illum::denoise::Denoiser;
use illum::metrics::compare;
use illum::render::{RenderSettings, Renderer};
use std::path::Path;

fn load(path: &str, width: u32) -> illum::scene::Scene {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    let mut s = illum::scene::load(&p).unwrap_or_else(|e| panic!("{e}"));
    s.camera.set_resolution(Some(width), None).unwrap();
    s
}

fn mean(image: &[[f32; 3]]) -> [f64; 3] {
    let n = image.len() as f64;
    std::array::from_fn(|c| image.iter().map(|p| f64::from(p[c])).sum::<f64>() / n)
}

#[test]
fn denoising_lowers_the_error_of_a_16_spp_render_and_keeps_its_mean() {
    let ctx = context();
    let r = Renderer::new(ctx.clone());
    let d = Denoiser::new().unwrap_or_else(|e| panic!("{e}"));
    for (path, width) in [
        ("scenes/default.json", 256),
        ("scenes/veach.json", 192),
        ("scenes/bench/dome-occluders.json", 128),
    ] {
        let scene = load(path, width);
        let render = |spp, seed| {
            let settings = RenderSettings {
                spp,
                seed,
                trace: trace_mode(),
                ..Default::default()
            };
            r.render(&scene, &settings, &mut |_, _| {}).unwrap().film
        };
        // The reference has seeds of its own: its noise is independent of the image's.
        let (image, reference) = (render(16, 1), render(256, 2));
        let denoised = d.denoise_film(&image).unwrap();
        let (before, after) = (
            compare(&image.beauty, &reference.beauty).relmse,
            compare(&denoised, &reference.beauty).relmse,
        );
        println!(
            "{path} at {}x{}, 16 spp: relMSE {before:.3e} -> {after:.3e} denoised ({:.1}x lower)",
            image.width,
            image.height,
            before / after
        );
        assert!(
            after < before,
            "{path}: denoising raised relMSE {before:.3e} -> {after:.3e}"
        );
        let (m, md) = (mean(&image.beauty), mean(&denoised));
        for c in 0..3 {
            let rel = (md[c] - m[c]).abs() / m[c];
            assert!(
                rel < 0.01,
                "{path}: channel {c}: denoised mean {} vs {} ({rel:.4})",
                md[c],
                m[c]
            );
        }
    }
    assert_no_validation_messages(&ctx);
}

#[test]
fn render_denoise_adds_a_layer_and_leaves_the_rest_as_rendered() {
    let scene = temp_path("denoise.json");
    std::fs::write(&scene, SMALL_SCENE).unwrap();
    let (plain, denoised) = (temp_path("plain.exr"), temp_path("denoised.exr"));
    for (out, extra) in [(&plain, None), (&denoised, Some("--denoise"))] {
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "--spp",
            "8",
            "-q",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend(extra);
        let (code, log) = illum_cli(&args);
        assert_eq!(code, 0, "{log}");
    }
    let (a, b) = (
        illum::output::read_exr(&plain).unwrap(),
        illum::output::read_exr(&denoised).unwrap(),
    );
    for (name, values) in &a.channels {
        let other = b.channels.iter().find(|c| &c.0 == name).unwrap();
        assert!(
            values
                .iter()
                .zip(&other.1)
                .all(|(x, y)| x.to_bits() == y.to_bits()),
            "{name} changed by --denoise"
        );
    }
    let layer: Vec<&String> = b
        .channels
        .iter()
        .map(|c| &c.0)
        .filter(|n| n.starts_with("Denoised."))
        .collect();
    assert_eq!(layer.len(), 3, "{layer:?}");
    let header = b.attributes.iter().find(|a| a.0 == "illum.denoiser");
    assert!(
        header.is_some_and(|h| h.1.contains("Open Image Denoise 2.")),
        "{header:?}"
    );

    // No library: the error says what to install, and nothing is rendered or written.
    let out = temp_path("nolib.exr");
    let run = illum_command()
        .env(
            "ILLUM_OIDN_LIBRARY",
            "/nonexistent/libOpenImageDenoise.so.2",
        )
        .args([
            "render",
            scene.to_str().unwrap(),
            "--spp",
            "8",
            "--denoise",
            "-o",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(
        err.contains("Open Image Denoise") && err.contains("setup-debian.sh"),
        "{err}"
    );
    assert!(!out.exists());
}
