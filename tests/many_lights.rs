//! Many lights (src/stress/many_lights.rs scenes): the light tree's image equals the brute-force
//! one (every light sampled at every shading point, `LightSelection::Loop`) within statistics.
//! Each image is the mean of BATCHES independent renders; the per-pixel variance comes from their
//! scatter, not from the renderer's Variance AOV. Per pixel and channel a Welch t-test, Šidák
//! over all of them, and the image mean per channel.

mod common;
use common::*;
use illum::render::{IntegratorSettings, LightSelection, RenderSettings, Renderer};
use illum::stress::many_lights::{ManyLights, scene_json};

fn compare(n: usize, w: u32, h: u32, spp_tree: u32, spp_loop: u32) {
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    let scene = scene(&scene_json(n, ManyLights::Mixed, w, h));
    let settings = |sel, spp, seed| RenderSettings {
        spp,
        seed,
        trace: trace_mode(),
        integrator: IntegratorSettings {
            light_selection: sel,
            ..Default::default()
        },
        ..Default::default()
    };
    let t0 = std::time::Instant::now();
    let tree = Batches::render(
        &renderer,
        &scene,
        &settings(LightSelection::Tree, spp_tree, 1),
        BATCHES,
    );
    let t1 = std::time::Instant::now();
    let brute = Batches::render(
        &renderer,
        &scene,
        &settings(LightSelection::Loop, spp_loop, 2),
        BATCHES,
    );
    eprintln!(
        "{n} lights: tree {:.1} s, loop {:.1} s",
        (t1 - t0).as_secs_f64(),
        t1.elapsed().as_secs_f64()
    );
    assert_eq!(tree.non_finite_samples + brute.non_finite_samples, 0);
    let dof = f64::from(BATCHES - 1);
    let tests = (tree.mean.len() * 3) as f64;
    let alpha = 1e-3f64;
    let per = 1.0 - (1.0 - alpha).powf(1.0 / tests);
    let (mut worst, mut sum_d, mut sum_v) = (0.0f64, [0.0; 3], [0.0; 3]);
    let mut parts: [Vec<(f64, f64)>; 3] = [vec![], vec![], vec![]];
    let mut lit = 0;
    for i in 0..tree.mean.len() {
        for c in 0..3 {
            let d = tree.mean[i][c] - brute.mean[i][c];
            let v = tree.var[i][c] + brute.var[i][c];
            sum_d[c] += d;
            sum_v[c] += v;
            parts[c].extend([(tree.var[i][c], dof), (brute.var[i][c], dof)]);
            if brute.mean[i][c] > 0.0 {
                lit += 1;
            }
            let t = t_for(
                per,
                welch_dof(&[(tree.var[i][c], dof), (brute.var[i][c], dof)]),
            );
            let floor = 1e-5 * brute.mean[i][c].abs() + 1e-7;
            worst = worst.max(d.abs() / v.sqrt().max(1e-300));
            assert!(
                d.abs() <= t * v.sqrt() + floor,
                "{n} lights, pixel {i} channel {c}: tree {} vs loop {} (t = {:.2}, limit {t:.2})",
                tree.mean[i][c],
                brute.mean[i][c],
                d / v.sqrt()
            );
        }
    }
    assert!(lit > tree.mean.len() * 2, "the scene must be lit");
    eprintln!("{n} lights: largest per-pixel |t| {worst:.2}");
    for c in 0..3 {
        let z = sum_d[c] / sum_v[c].sqrt();
        eprintln!(
            "{n} lights: image mean channel {c}: tree {:.5}, loop {:.5}, t = {z:.2}",
            tree.mean.iter().map(|p| p[c]).sum::<f64>() / tree.mean.len() as f64,
            brute.mean.iter().map(|p| p[c]).sum::<f64>() / brute.mean.len() as f64
        );
        let limit = t_for(alpha / 3.0, welch_dof(&parts[c]));
        assert!(
            z.abs() < limit,
            "{n} lights, channel {c}: image mean t = {z:.2} (limit {limit:.2})"
        );
    }
    assert_no_validation_messages(&ctx);
}

#[test]
fn tree_matches_brute_force_128_lights() {
    compare(128, 16, 12, 1024, 64);
}

#[test]
fn tree_matches_brute_force_1000_lights() {
    compare(1000, 12, 9, 2048, 64);
}
