//! Many lights (src/stress/many_lights.rs scenes): the light tree's image equals the brute-force
//! one (every light sampled at every shading point, `LightSelection::Loop`) within statistics.
//! Each image is the mean of BATCHES independent renders; the per-pixel variance comes from their
//! scatter, not from the renderer's Variance AOV. Per 2 x 2 block of pixels and channel a Welch
//! t-test, Šidák over all of them, and the image mean per channel.

mod common;
use common::*;
use illum::integrators::{Direct, DirectLighting, LightSelection};
use illum::render::{RenderSettings, Renderer};
use illum::stress::many_lights::{ManyLights, scene_json};

/// A block's summed difference and the (variance, dof) parts of its variance.
type BlockSum = (f64, Vec<(f64, f64)>);

fn compare(n: usize, w: u32, h: u32, spp_tree: u32, spp_loop: u32) {
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    let scene = scene(&scene_json(n, ManyLights::Mixed, w, h));
    let settings = |sel, spp, seed| RenderSettings {
        spp,
        seed,
        trace: trace_mode(),
        integrator: Direct(DirectLighting {
            light_selection: sel,
            ..Default::default()
        })
        .into(),
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
    // Per 2 x 2 block of pixels and channel a Welch t-test, Šidák over the blocks. Not per pixel:
    // a pick from the tree is heavy-tailed, and the Šidák quantile over every pixel (about 2e-6
    // each) lies where 16 batch means are not yet normal: six seed pairs of the 128-light case
    // gave a largest per-pixel |t| of 3.2 to 6.8 against a limit of about 6, with image means
    // equal (|t| < 1.9). Four pixels' sums are nearer normal, not normal: one of those pairs
    // reaches 5.8 in a block (limit 5.4), and 4.3 at 8x the samples, so a fluctuation, not a
    // bias. A tree pmf wrong over a region still shows in its blocks and in the image mean.
    let dof = f64::from(BATCHES - 1);
    let (bw, bh) = (w.div_ceil(2) as usize, h.div_ceil(2) as usize);
    let mut blocks: Vec<[BlockSum; 3]> = vec![Default::default(); bw * bh];
    let (mut sum_d, mut sum_v) = ([0.0; 3], [0.0; 3]);
    let mut parts: [Vec<(f64, f64)>; 3] = [vec![], vec![], vec![]];
    let mut lit = 0;
    for i in 0..tree.mean.len() {
        let (x, y) = (i % w as usize, i / w as usize);
        let b = &mut blocks[(y / 2) * bw + x / 2];
        for c in 0..3 {
            let d = tree.mean[i][c] - brute.mean[i][c];
            sum_d[c] += d;
            sum_v[c] += tree.var[i][c] + brute.var[i][c];
            parts[c].extend([(tree.var[i][c], dof), (brute.var[i][c], dof)]);
            if brute.mean[i][c] > 0.0 {
                lit += 1;
            }
            b[c].0 += d;
            b[c].1
                .extend([(tree.var[i][c], dof), (brute.var[i][c], dof)]);
        }
    }
    let alpha = 1e-3f64;
    let per = 1.0 - (1.0 - alpha).powf(1.0 / (blocks.len() * 3) as f64);
    let mut worst = 0.0f64;
    for (k, b) in blocks.iter().enumerate() {
        for (c, (d, all)) in b.iter().enumerate() {
            let v: f64 = all.iter().map(|p| p.0).sum();
            let t = t_for(per, welch_dof(all));
            worst = worst.max(d.abs() / v.sqrt().max(1e-300));
            assert!(
                d.abs() <= t * v.sqrt() + 1e-7,
                "{n} lights, block {k} channel {c}: tree - loop summed over the block {d} (t = {:.2}, limit {t:.2})",
                d / v.sqrt()
            );
        }
    }
    assert!(lit > tree.mean.len() * 2, "the scene must be lit");
    eprintln!("{n} lights: largest per-block |t| {worst:.2}");
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
