//! Indirect lighting (issue 11): the path tracer and the full integrator (direct lighting, the
//! radiosity cache, reflections) against closed forms first (the furnace, an open plane under a
//! uniform dome), then against each other: the cache against brute force on the interior scene,
//! full against path where no caustic paths exist, the AOVs against the beauty, split renders
//! against the render in one piece, and the cache left out where nothing reads it.
//!
//! Statistics: means over pixels or blocks of pixels, with standard errors from independent
//! seeds (never from the render's own variance report), and Šidák-corrected limits.

mod common;
use common::*;
use illum::output::Film;
use illum::render::{IntegratorKind, IntegratorSettings, RenderOutput, RenderSettings, Renderer};
use illum::scene::Scene;
use std::sync::{Arc, Mutex};

fn settings(kind: IntegratorKind, spp: u32) -> RenderSettings {
    RenderSettings {
        spp,
        trace: trace_mode(),
        integrator: IntegratorSettings {
            kind,
            ..Default::default()
        },
        ..Default::default()
    }
}

fn render_seeds(ctx: &illum::vk::Context, scene: &Scene, s: &RenderSettings, seeds: &[u64]) -> Vec<RenderOutput> {
    Renderer::new(ctx.clone())
        .render_seeds(scene, s, seeds, &mut |_, _| {})
        .unwrap_or_else(|e| panic!("render failed: {e}"))
}

fn plane<'a>(film: &'a Film, name: &str) -> &'a [[f32; 3]] {
    &film
        .aovs
        .iter()
        .find(|p| p.name == name)
        .unwrap_or_else(|| panic!("no AOV plane {name}"))
        .rgb
}

fn luminance(c: [f32; 3]) -> f64 {
    0.2126 * f64::from(c[0]) + 0.7152 * f64::from(c[1]) + 0.0722 * f64::from(c[2])
}

/// Mean luminance of each block x block pixel block, per seed: [seed][block].
fn block_means(outs: &[RenderOutput], block: u32) -> Vec<Vec<f64>> {
    outs.iter()
        .map(|o| {
            let f = &o.film;
            let (bx, by) = (f.width / block, f.height / block);
            let mut m = vec![0.0; (bx * by) as usize];
            for y in 0..by * block {
                for x in 0..bx * block {
                    m[((y / block) * bx + x / block) as usize] +=
                        luminance(f.beauty[(y * f.width + x) as usize]);
                }
            }
            m.iter().map(|v| v / f64::from(block * block)).collect()
        })
        .collect()
}

/// Mean over seeds and its standard error (from the seeds' scatter), per block.
fn mean_and_error(per_seed: &[Vec<f64>]) -> Vec<(f64, f64)> {
    let k = per_seed.len() as f64;
    (0..per_seed[0].len())
        .map(|b| {
            let m = per_seed.iter().map(|s| s[b]).sum::<f64>() / k;
            let var = per_seed.iter().map(|s| (s[b] - m).powi(2)).sum::<f64>() / (k - 1.0);
            (m, (var / k).sqrt())
        })
        .collect()
}

/// Two-sided normal quantile for a family-wise level of 1e-3 over `n` tests (Šidák).
fn sidak_z(n: usize) -> f64 {
    let alpha = 1.0 - (1.0f64 - 1e-3).powf(1.0 / n as f64);
    // Acklam-free bound: the normal tail is below exp(-z^2/2)/2 for z >= 1, so this z is
    // conservative.
    (2.0 * (1.0 / alpha).ln()).sqrt()
}

/// A closed sphere of uniform emission Le = 1 and diffuse albedo rho, seen from inside: every
/// pixel is Le / (1 - rho) (all bounces).
fn furnace(rho: f64) -> Scene {
    scene(&format!(
        r#"{{"camera": {{"position": [0.2, 0.1, 0.3], "look_at": [0, 0, -1], "fov_y": 90, "resolution": [12, 12]}},
             "materials": {{"shell": {{"diffuse": [{rho}, {rho}, {rho}], "emission": [1, 1, 1], "two_sided": true}}}},
             "shapes": {{"s": {{"sphere": {{"center": [0, 0, 0], "radius": 2}}, "material": "shell"}}}}}}"#
    ))
}

#[test]
fn furnace_explore() {
    let ctx = context();
    for rho in [0.5, 0.9] {
        let truth = 1.0 / (1.0 - rho);
        let s = furnace(rho);
        for kind in [IntegratorKind::Path, IntegratorKind::Full] {
            let outs = render_seeds(&ctx, &s, &settings(kind, 16), &[1, 2, 3, 4, 5, 6, 7, 8]);
            let m = mean_and_error(&block_means(&outs, 12));
            eprintln!("rho {rho} {kind:?}: {:.6} ± {:.6} (truth {truth}) rel {:.2e}", m[0].0, m[0].1, m[0].0 / truth - 1.0);
        }
    }
    assert_no_validation_messages(&ctx);
}

fn interior(diffuse_only: bool) -> Scene {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/interior.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["camera"]["resolution"] = serde_json::json!([48, 36]);
    if diffuse_only {
        v["materials"]["glossy"] = serde_json::json!({"diffuse": [0.2, 0.3, 0.6]});
        v["materials"]["mirror"] = serde_json::json!({"diffuse": [0.8, 0.8, 0.8]});
    }
    scene(&v.to_string())
}

#[test]
fn interior_explore() {
    let ctx = context();
    let seeds: Vec<u64> = (1..=8).collect();
    for (name, s, a, b) in [
        ("cache vs off", interior(false), IntegratorKind::Full, None),
        ("full vs path (diffuse)", interior(true), IntegratorKind::Full, Some(IntegratorKind::Path)),
    ] {
        let ra = render_seeds(&ctx, &s, &settings(a, 32), &seeds);
        let mut sb = settings(b.unwrap_or(a), 32);
        if b.is_none() {
            sb.integrator.radiosity_cache = false;
        }
        let rb = render_seeds(&ctx, &s, &sb, &seeds);
        let ma = mean_and_error(&block_means(&ra, 6));
        let mb = mean_and_error(&block_means(&rb, 6));
        let mut worst = (0.0f64, 0.0f64);
        for (i, (x, y)) in ma.iter().zip(&mb).enumerate() {
            eprintln!("block {i}: {:.4} ± {:.4} vs {:.4} ± {:.4}", x.0, x.1, y.0, y.1);
            let z = (x.0 - y.0) / (x.1 * x.1 + y.1 * y.1).sqrt();
            let rel = (x.0 - y.0) / y.0;
            if z.abs() > worst.0.abs() { worst.0 = z; }
            if rel.abs() > worst.1.abs() { worst.1 = rel; }
        }
        let ta: f64 = ra.iter().map(|o| o.stats.render_seconds).sum();
        let tb: f64 = rb.iter().map(|o| o.stats.render_seconds).sum();
        eprintln!("{name}: worst z {:.2}, worst rel {:.3}, {} blocks, sidak {:.2}; times {ta:.2} / {tb:.2}", worst.0, worst.1, ma.len(), sidak_z(ma.len()));
        eprintln!("{:?}", ra[0].stats.integrator);
    }
    let _ = Arc::new(Mutex::new(0));
    assert_no_validation_messages(&ctx);
}
