//! Adaptive pixel sampling (`--noise-threshold`, src/render/adaptive.rs): unbiased (per-pixel
//! t-tests over independent renders against the closed form of a Lambert floor under a rect
//! light), on target (the error against converged references of three scenes is at most T²),
//! split renders by sample range and by tile merge bit-identically to one render, and the command
//! line refuses bad values naming them and writes each pixel's count.

mod common;
use common::*;
use glam::DVec3;
use illum::integrators::{Direct, DirectLighting, Technique};
use illum::jobs::{Part, merge};
use illum::render::adaptive::{Adaptive, Target};
use illum::render::{RenderOutput, RenderSettings, Renderer};
use illum::scene::Scene;
use std::path::Path;

fn render(r: &Renderer, scene: &Scene, s: &RenderSettings) -> RenderOutput {
    r.render(scene, s, &mut |_, _| {})
        .unwrap_or_else(|e| panic!("render: {e}"))
}

/// The counts of an adaptive render: with a threshold, every one a power of two from the
/// minimum, or the cap; with a mean, from an eighth of it to the cap (their cost, in rays, is
/// that of the mean: src/render/adaptive.rs tests `spread`).
fn counts(out: &RenderOutput, t: Adaptive, cap: u32) -> Vec<u32> {
    let c: Vec<u32> = out
        .film
        .samples
        .as_ref()
        .expect("the counts differ, so the film has its SampleCount plane")
        .iter()
        .map(|&c| c as u32)
        .collect();
    match t.target {
        Target::Threshold(_) => {
            for &n in &c {
                assert!(
                    n == cap || (n >= t.min_spp && n < cap && n.is_power_of_two()),
                    "count {n} (min {}, cap {cap})",
                    t.min_spp
                );
            }
        }
        Target::Mean(mean) => {
            let lo = (mean / 8).max(1);
            assert!(
                c.iter().all(|&x| x >= lo && x <= cap),
                "counts {c:?} (from {lo} to {cap})"
            );
        }
    }
    c
}

#[test]
fn adaptive_sampling_is_unbiased() {
    // A 4 x 4 rect light 0.4 above a Lambert floor (tests/stratified.rs's closed form): the
    // noise falls off away from it, so counts range from the minimum to the cap.
    const W: u32 = 12;
    const CAP: u32 = 256;
    let (albedo, camera, fov) = (0.5, DVec3::new(1.0, 0.3, 0.2), 20.0);
    let (l, h, s) = (2.0, 0.4, 2.0);
    let json = format!(
        r#"{{"camera": {{"position": [1.0, 0.3, 0.2], "look_at": [0, 0, 0], "fov_y": {fov}, "resolution": [{W}, {W}]}},
            "materials": {{"m": {{"diffuse": [{albedo}, {albedo}, {albedo}]}}}},
            "shapes": {{"floor": {{"rect": {{"center": [0, 0, 0], "normal": [0, 1, 0], "size": [40, 40]}}, "material": "m"}}}},
            "lights": {{"l": {{"rect": {{"center": [0, {h}, 0], "normal": [0, -1, 0], "size": [{}, {}]}}, "intensity": {l}}}}}}}"#,
        2.0 * s,
        2.0 * s
    );
    let scene = scene(&json);
    let ctx = context();
    let r = Renderer::new(ctx.clone());
    let t = Adaptive::threshold(0.06, 4);
    // One light sample, light sampling only: noisy enough that the counts spread (8 to 256).
    let settings = RenderSettings {
        spp: CAP,
        seed: 5,
        trace: trace_mode(),
        integrator: std::sync::Arc::new(Direct(DirectLighting {
            technique: Technique::Light,
            light_samples: 1,
            ..Default::default()
        })),
        adaptive: Some(t),
        ..Default::default()
    };
    let c = counts(&render(&r, &scene, &settings), t, CAP);
    let (lo, hi) = (c.iter().min().unwrap(), c.iter().max().unwrap());
    eprintln!("counts from {lo} to {hi}");
    assert!(
        lo < hi,
        "the counts must vary for this test to mean anything"
    );
    let irradiance = square_light_irradiance(l, h, s);
    let b = Batches::render(
        &r,
        &scene,
        &RenderSettings {
            spp: CAP * BATCHES,
            ..settings
        },
        BATCHES,
    );
    let pts = floor_points(camera, fov, W, W);
    assert_lambert_floor(&b, &pts, albedo, irradiance);
    assert_no_validation_messages(&ctx);
}

#[test]
fn adaptive_sampling_agrees_with_uniform_sampling() {
    // A textured sky with a sun, glossy and diffuse spheres and their shadows: per-pixel Welch
    // tests of adaptive against uniform renders, BATCHES each, family-wise 0.01.
    let ctx = context();
    let r = Renderer::new(ctx.clone());
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bench/dome.json");
    let mut scene = illum::scene::load(&dir).unwrap_or_else(|e| panic!("{e}"));
    (scene.camera.width, scene.camera.height) = (24, 18);
    const CAP: u32 = 128;
    let uniform = RenderSettings {
        spp: CAP,
        seed: 9,
        trace: trace_mode(),
        ..Default::default()
    };
    let batches = |s: &RenderSettings| {
        Batches::render(
            &r,
            &scene,
            &RenderSettings {
                spp: CAP * BATCHES,
                ..s.clone()
            },
            BATCHES,
        )
    };
    let u = batches(&uniform);
    let tests = (u.mean.len() * 3) as f64;
    let per = 1.0 - (1.0 - 0.01f64).powf(1.0 / tests);
    // Welch's dof is at least that of one batch set: the limit is conservative.
    let limit = t_for(per, f64::from(BATCHES - 1));
    let mut worst = 0.0f64;
    for t in [Adaptive::threshold(0.05, 8), Adaptive::mean(32, 8)] {
        let adaptive = RenderSettings {
            adaptive: Some(t),
            seed: 10,
            ..uniform.clone()
        };
        let c = counts(&render(&r, &scene, &adaptive), t, CAP);
        assert!(
            c.iter().min() < c.iter().max(),
            "{t:?}: the counts must vary"
        );
        let a = batches(&adaptive);
        for i in 0..a.mean.len() {
            for ch in 0..3 {
                let d = a.mean[i][ch] - u.mean[i][ch];
                let sd = (a.var[i][ch] + u.var[i][ch]).sqrt();
                let floor = 1e-5 * u.mean[i][ch].abs() + 1e-6;
                worst = worst.max((d.abs() - floor).max(0.0) / sd.max(1e-300));
                assert!(
                    d.abs() <= limit * sd + floor,
                    "{t:?}: pixel {i} channel {ch}: adaptive {} vs uniform {} (t = {:.2}, limit {limit:.2})",
                    a.mean[i][ch],
                    u.mean[i][ch],
                    d / sd
                );
            }
        }
    }
    eprintln!("largest |t|: {worst:.2} (limit {limit:.2})");
    assert_no_validation_messages(&ctx);
}

#[test]
fn the_noise_threshold_reaches_its_target() {
    let ctx = context();
    let r = Renderer::new(ctx.clone());
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let load = |path: &str, w: u32, h: u32| {
        let mut s = illum::scene::load(&dir.join(path)).unwrap_or_else(|e| panic!("{e}"));
        s.camera.width = w;
        s.camera.height = h;
        s
    };
    const T: f64 = 0.05;
    let t = Adaptive::threshold(T, 16);
    const CAP: u32 = 1024;
    for (name, scene) in [
        (
            "small",
            illum::scene::from_json_str(SMALL_SCENE, "<small>", Path::new(".")).unwrap(),
        ),
        ("bench/dome", load("bench/dome.json", 40, 30)),
        ("veach", load("veach.json", 48, 36)),
    ] {
        let uniform = |spp, seed| RenderSettings {
            spp,
            seed,
            trace: trace_mode(),
            ..Default::default()
        };
        let reference = render(&r, &scene, &uniform(4096, 1000));
        // The reference's own squared error, per pixel: its Variance plane (s² / n, an
        // overestimate under stratified samples), subtracted from the measured error.
        let ref_var = reference.film.variance.as_ref().unwrap();
        let out = render(
            &r,
            &scene,
            &RenderSettings {
                adaptive: Some(t),
                ..uniform(CAP, 3)
            },
        );
        let c = counts(&out, t, CAP);
        let (mut err, mut n) = (0.0, 0.0);
        for (i, (p, q)) in out
            .film
            .beauty
            .iter()
            .zip(&reference.film.beauty)
            .enumerate()
        {
            for ch in 0..3 {
                let d = f64::from(p[ch]) - f64::from(q[ch]);
                let e = d * d - f64::from(ref_var[i][ch]);
                err += e / (f64::from(q[ch]).powi(2) + illum::metrics::RELMSE_EPSILON);
                n += 1.0;
            }
        }
        let relmse = err / n;
        let mean_count = c.iter().map(|&x| f64::from(x)).sum::<f64>() / c.len() as f64;
        eprintln!(
            "{name}: relMSE {relmse:.3e} = {:.3} T², {mean_count:.1} samples a pixel on average \
             (min {}, max {})",
            relmse / (T * T),
            c.iter().min().unwrap(),
            c.iter().max().unwrap()
        );
        assert!(
            relmse <= T * T,
            "{name}: relMSE {relmse:.3e} above the target {:.3e}",
            T * T
        );
        assert!(
            mean_count < f64::from(CAP) / 2.0,
            "{name}: {mean_count} samples a pixel on average: the threshold stopped too few"
        );
    }
    assert_no_validation_messages(&ctx);
}

#[test]
fn adaptive_renders_split_and_merged_equal_one_render() {
    let ctx = context();
    let scene = scene(SMALL_SCENE);
    let r = Renderer::new(ctx.clone());
    for t in [Adaptive::threshold(0.03, 8), Adaptive::mean(64, 8)] {
        let settings = |samples, crop| RenderSettings {
            spp: 600,
            seed: 7,
            trace: trace_mode(),
            samples,
            crop,
            adaptive: Some(t),
            ..Default::default()
        };
        let whole = render(&r, &scene, &settings(None, None));
        let c = counts(&whole, t, 600);
        assert!(
            c.iter().min() < c.iter().max(),
            "{t:?}: the counts must vary"
        );
        // Sample ranges: unaligned ends, one inside a block, some past every pixel's count.
        let ranges = [(0, 100), (100, 256), (256, 520), (520, 600)];
        let parts: Vec<Part> = ranges
            .iter()
            .map(|&(a, b)| {
                render_part(
                    &r,
                    &scene,
                    &settings(Some((a, b)), None),
                    &format!("adaptive-s{a}"),
                )
            })
            .collect();
        assert_eq!(
            merge(&parts).unwrap().film,
            whole.film,
            "{t:?}: sample ranges"
        );
        let parts: Vec<Part> = ODD_TILES_13X9
            .iter()
            .map(|w| {
                render_part(
                    &r,
                    &scene,
                    &settings(None, Some(*w)),
                    &format!("adaptive-c{w}"),
                )
            })
            .collect();
        assert_eq!(merge(&parts).unwrap().film, whole.film, "{t:?}: tiles");
    }
    assert_no_validation_messages(&ctx);
}

#[test]
fn the_command_line_checks_the_threshold_and_writes_the_counts() {
    let out = temp_path("adaptive-cli.exr");
    let o = out.to_str().unwrap();
    for (args, expected) in [
        (
            vec!["--noise-threshold", "0"],
            "--noise-threshold must be a positive",
        ),
        (
            vec!["--noise-threshold", "nan"],
            "--noise-threshold must be a positive",
        ),
        (
            vec!["--noise-threshold", "0.1", "--min-spp", "3"],
            "--min-spp must be a power of two",
        ),
        (
            vec!["--noise-threshold", "0.1", "--spp", "16"],
            "needs --spp",
        ),
        (vec!["--adaptive", "--spp", "8"], "--adaptive spreads"),
        (
            vec!["--adaptive", "--noise-threshold", "0.1"],
            "cannot be used with",
        ),
    ] {
        let mut all = vec!["render", "--width", "32", "-o", o, "--quiet"];
        all.extend(&args);
        let (code, err) = illum_cli(&all);
        assert_ne!(code, 0, "{args:?}");
        assert!(err.contains(expected), "{args:?}: {err}");
    }
    // Renders the default scene 32 pixels wide with `flags`: its counts and a header attribute.
    let render = |flags: &[&str], attribute: &str| {
        let mut all = vec!["render", "--width", "32", "-o", o, "--quiet"];
        all.extend(flags);
        let (code, err) = illum_cli(&all);
        assert_eq!(code, 0, "{flags:?}: {err}");
        let img = illum::output::read_exr(&out).unwrap();
        let counts = img
            .channels
            .iter()
            .find(|(n, _)| n == "SampleCount")
            .map(|(_, c)| c.clone())
            .expect("a SampleCount channel");
        let value = img
            .attributes
            .iter()
            .find(|(n, _)| n == attribute)
            .map(|(_, v)| v.clone());
        (counts, value)
    };
    let (counts, t) = render(
        &["--noise-threshold", "0.05", "--spp", "64"],
        "illum.noiseThreshold",
    );
    assert!(counts.iter().all(|&c| (16.0..=64.0).contains(&c)));
    assert!(counts.iter().any(|&c| c < 64.0), "some pixel stops early");
    assert_eq!(t.as_deref(), Some("0.05"));
    // The cost of 32 samples a pixel, spread over the pixels: from 4 to 16 x 32 each.
    let (counts, n) = render(&["--adaptive", "--spp", "32"], "illum.adaptiveMeanSpp");
    assert!(counts.iter().all(|&c| (4.0..=512.0).contains(&c)));
    assert!(counts.iter().any(|&c| c != counts[0]), "the counts vary");
    assert_eq!(n.as_deref(), Some("32"));
}
