//! The camera-sample streams (glsl/shared/common.glsl `rng_init_camera`, through
//! tests/kernels/rng_check.comp): shuffled, Owen-scrambled Sobol pairs. Their structure is checked
//! exactly (the first 2^17 even, or odd, samples of a split pixel, and the first 2^17 samples of
//! a pixel of one sequence, put one point of every pair in each elementary interval of area
//! 2^-17, and every prefix floor(n/2^m) or one more point in each of area 2^-m), and their
//! randomization by chi-square tests over many
//! pixels: each point uniform, and pairs of one sample, and the even and the odd sequence,
//! independent of each other.

mod common;

use common::*;

fn draw(k: &Kernel, inputs: &[[u32; 4]]) -> Vec<[f32; 4]> {
    k.run(&[0u32; 4], inputs, 0, inputs.len(), 0, inputs.len())
}

/// Chi-square test of `points` against the uniform density on a `bins` × `bins` grid.
fn chi2_uniform_2d(what: &str, points: &[(f32, f32)], bins: usize) {
    let mut counts = vec![0u32; bins * bins];
    for &(x, y) in points {
        assert!(
            (0.0..1.0).contains(&x) && (0.0..1.0).contains(&y),
            "{what}: ({x}, {y})"
        );
        let (i, j) = ((x * bins as f32) as usize, (y * bins as f32) as usize);
        counts[j * bins + i] += 1;
    }
    let expected = points.len() as f64 / (bins * bins) as f64;
    let chi2: f64 = counts
        .iter()
        .map(|&c| (f64::from(c) - expected).powi(2) / expected)
        .sum();
    let dof = (bins * bins - 1) as f64;
    let p = chi2_sf(chi2, dof);
    eprintln!("{what}: chi2 = {chi2:.1}, dof = {dof}, p = {p:.3e}");
    assert!(
        p > alpha(),
        "{what}: chi2 = {chi2:.1} for {dof} dof, p = {p:.3e}"
    );
}

#[test]
fn camera_streams_are_scrambled_sobol_nets() {
    let ctx = context();
    let k = Kernel::new(&ctx, "rng_check", illum_test_kernels::RNG_CHECK_PLAIN);
    // 2^17 points: the Sobol matrix's every step (bits 16 and up too) shapes some interval.
    const M: u32 = 17;
    for (seed, pixel) in [(7u32, 12345u32), (0xdead_beef, 3)] {
        for pair in [0u32, 5] {
            // Parity 0 and 1: a split pixel's even and odd samples; 2: a pixel of one sequence
            // (bit 31 of the kernel's word), sample j, which must be the split pixel's sample 2j.
            for parity in [0u32, 1, 2] {
                let inputs: Vec<[u32; 4]> = (0..1u32 << M)
                    .map(|j| match parity {
                        2 => [seed, pixel, j, pair | 1 << 31],
                        _ => [seed, pixel, 2 * j + parity, pair],
                    })
                    .collect();
                let out = draw(&k, &inputs);
                if parity == 2 {
                    let even: Vec<[u32; 4]> = (0..1u32 << 10)
                        .map(|j| [seed, pixel, 2 * j, pair])
                        .collect();
                    assert_eq!(
                        draw(&k, &even),
                        out[..1 << 10],
                        "seed {seed} pixel {pixel} pair {pair}: one sequence is not a split \
                         pixel's even samples"
                    );
                }
                // Every shape of elementary interval: 2^a columns by 2^(M - a) rows.
                for a in 0..=M {
                    let (cols, rows) = (1u32 << a, 1u32 << (M - a));
                    let mut seen = vec![false; 1 << M];
                    for o in &out {
                        let cell =
                            ((o[1] * rows as f32) as u32) * cols + (o[0] * cols as f32) as u32;
                        assert!(
                            !std::mem::replace(&mut seen[cell as usize], true),
                            "seed {seed} pixel {pixel} pair {pair} parity {parity}: two points in \
                             one {cols} x {rows} interval"
                        );
                    }
                }
                // Every prefix is stratified too, not only powers of two: the first n
                // points put floor(n / 2^m) or one more into each interval of area 2^-m, for
                // every m and shape (whole aligned blocks are nets; the rest of a block puts
                // at most one point in each).
                for n in [44usize, 1000, 3 * 4096 + 77, (1 << M) - 1] {
                    for m in 0..=M {
                        let q = (n >> m) as u32;
                        for a in 0..=m {
                            let (cols, rows) = (1u32 << a, 1u32 << (m - a));
                            let mut count = vec![0u32; 1 << m];
                            for o in &out[..n] {
                                let cell = ((o[1] * rows as f32) as u32) * cols
                                    + (o[0] * cols as f32) as u32;
                                count[cell as usize] += 1;
                            }
                            assert!(
                                count.iter().all(|&c| c == q || c == q + 1),
                                "seed {seed} pixel {pixel} pair {pair} parity {parity}: the first \
                                 {n} points are not stratified in {cols} x {rows} intervals"
                            );
                        }
                    }
                }
            }
        }
    }
    assert_no_validation_messages(&ctx);
}

/// A group of 2^s light or BRDF samples at one shading point (glsl/direct/direct.glsl `group_u`:
/// `rng_sobol2_group`, one dimension pair for the group): each camera sample's group is a net
/// (one point in every elementary interval of area 2^-s, so every row, column and grid-cell
/// stratum holds one), and across a pixel's camera samples the groups stay stratified at every
/// prefix, as the pair's own sequence is.
#[test]
fn groups_of_samples_are_nets_and_stratified_across_camera_samples() {
    let ctx = context();
    let k = Kernel::new(&ctx, "rng_check", illum_test_kernels::RNG_CHECK_PLAIN);
    const S: u32 = 3;
    const M: u32 = 15;
    let group = 1usize << S;
    for (seed, pixel, pair) in [(7u32, 99u32, 4u32), (0x1234_5678, 70_000, 9)] {
        // Camera samples 0, 2, 4, …: the even sequence, in order, each with its group.
        let inputs: Vec<[u32; 4]> = (0..1u32 << (M - S))
            .flat_map(|c| {
                (0..group as u32).map(move |j| [seed, pixel, 2 * c, pair | j << 8 | S << 24])
            })
            .collect();
        let out = draw(&k, &inputs);
        let cells = |pts: &[[f32; 4]], cols: u32, rows: u32| -> Vec<u32> {
            let mut count = vec![0u32; (cols * rows) as usize];
            for o in pts {
                count[(((o[1] * rows as f32) as u32) * cols + (o[0] * cols as f32) as u32)
                    as usize] += 1;
            }
            count
        };
        for (c, g) in out.chunks(group).enumerate() {
            for a in 0..=S {
                let count = cells(g, 1 << a, 1 << (S - a));
                assert!(
                    count.iter().all(|&n| n == 1),
                    "seed {seed} pixel {pixel}: camera sample {c}'s group is not a net in {} x {} intervals",
                    1 << a,
                    1 << (S - a)
                );
            }
        }
        // The first n camera samples' groups: floor(n 2^s / 2^m) or one more point in each
        // interval of area 2^-m, for every m and shape.
        for n in [1usize, 3, 44, 1000, (1 << (M - S)) - 1] {
            let pts = &out[..n * group];
            for m in 0..=M {
                let q = (pts.len() >> m) as u32;
                for a in 0..=m {
                    let count = cells(pts, 1 << a, 1 << (m - a));
                    assert!(
                        count.iter().all(|&c| c == q || c == q + 1),
                        "seed {seed} pixel {pixel}: the first {n} camera samples' groups are not stratified in {} x {} intervals",
                        1 << a,
                        1 << (m - a)
                    );
                }
            }
        }
        // Each point is uniform over pixels (the scrambles): point 3 of camera sample 10.
        let inputs: Vec<[u32; 4]> = (0..1u32 << 16)
            .map(|p| [seed, p, 10, pair | 3 << 8 | S << 24])
            .collect();
        let pts: Vec<(f32, f32)> = draw(&k, &inputs).iter().map(|o| (o[0], o[1])).collect();
        chi2_uniform_2d("group point 3 at camera sample 10", &pts, 16);
    }
    assert_no_validation_messages(&ctx);
}

#[test]
fn camera_streams_are_uniform_and_independent() {
    let ctx = context();
    let k = Kernel::new(&ctx, "rng_check", illum_test_kernels::RNG_CHECK_PLAIN);
    const N: u32 = 1 << 16;
    // Over pixels, at a fixed sample index and pair: (seed, pixel, index, pair).
    let at = |index: u32, pair: u32| -> Vec<[f32; 4]> {
        let inputs: Vec<[u32; 4]> = (0..N).map(|p| [11, p, index, pair]).collect();
        draw(&k, &inputs)
    };
    let a = at(6, 2);
    let b = at(6, 3);
    let odd = at(7, 2);
    // (coordinate i of p, coordinate j of q) per pixel.
    let zip = |p: &[[f32; 4]], q: &[[f32; 4]], i: usize, j: usize| -> Vec<(f32, f32)> {
        p.iter().zip(q).map(|(p, q)| (p[i], q[j])).collect()
    };
    chi2_uniform_2d("pair 2 at sample 6", &zip(&a, &a, 0, 1), 16);
    chi2_uniform_2d("pairs 2 and 3 of one sample (x, x)", &zip(&a, &b, 0, 0), 16);
    let what = "samples 6 and 7: the even and the odd sequence (y, y)";
    chi2_uniform_2d(what, &zip(&a, &odd, 1, 1), 16);
    // Sample 0 of every pixel: the first points of the sequences are random too.
    let first = at(0, 0);
    chi2_uniform_2d("pair 0 at sample 0", &zip(&first, &first, 0, 1), 16);
    assert_no_validation_messages(&ctx);
}
