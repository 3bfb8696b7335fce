//! The dome's sampling tables: cell shaping, the guides and the row-by-row build, on the host.

use super::*;
use glam::Vec4;

#[test]
fn cell_excess_is_the_squared_coefficient_of_variation() {
    // One bilinear patch with corners (1, 0, 0, 0): f = (1 - x)(1 - y), E[f] = 1/4,
    // E[f^2] = 1/9, so the excess is 16/9 - 1.
    let stride = 4;
    let mut nodes = vec![0.0f32; stride * 4];
    nodes[stride + 1] = 1.0;
    let e = cell_excess(DOME_SHAPE_CORNERS, &nodes, stride, 0, 0);
    assert!((e - 7.0 / 9.0).abs() < 1e-12, "{e}");
    // A constant patch, and illum's tent over a constant neighbourhood: no excess.
    let flat = vec![2.5f32; stride * 4];
    assert!(cell_excess(DOME_SHAPE_CORNERS, &flat, stride, 0, 0).abs() < 1e-12);
    assert!(cell_excess(DOME_SHAPE_TENT, &flat, stride, 1, 1).abs() < 1e-12);
    // A lone hot texel under illum's bilinear lookup: its own cell's nodes are 1 at the
    // centre, 1/2 at the edges and 1/4 at the corners: E[f] = 9/16 and E[f^2] = (7/12)^2
    // (separable: each axis has E[a] = 3/4, E[a^2] = 7/12).
    let mut hot = vec![0.0f32; stride * 4];
    hot[2 * stride + 2] = 1.0;
    let e = cell_excess(DOME_SHAPE_TENT, &hot, stride, 1, 1);
    let want = (7.0f64 / 12.0).powi(2) / (9.0f64 / 16.0).powi(2) - 1.0;
    assert!((e - want).abs() < 1e-12, "{e} vs {want}");
}

#[test]
fn only_cells_that_vary_are_shaped() {
    let (w, h) = (8u32, 4u32);
    let flat = build(
        &Texture::new("flat", w, h, vec![Vec4::ONE; (w * h) as usize]),
        Vec3::ONE,
        DomeConvention::Illum,
    );
    // Nothing varies: uniform, no nodes.
    assert_eq!(flat.shape, DOME_SHAPE_UNIFORM);
    assert!(flat.nodes.is_empty() && flat.nodes_width == 0);
    let mut texels = vec![Vec4::ONE; (w * h) as usize];
    texels[(w + 3) as usize] = Vec4::splat(100.0);
    let hot = build(
        &Texture::new("hot", w, h, texels),
        Vec3::ONE,
        DomeConvention::Mitsuba,
    );
    assert_eq!(hot.shape, DOME_SHAPE_CORNERS);
    let shaped: Vec<(i64, i64)> = (0..hot.height as i64)
        .flat_map(|j| (0..hot.width as i64).map(move |i| (i, j)))
        .filter(|&(i, j)| hot.nodes[((j + 1) * (w as i64 + 2) + i + 1) as usize].is_sign_negative())
        .collect();
    // Mitsuba's cells with texel (3, 1) as a corner: (2, 0), (3, 0), (2, 1), (3, 1).
    assert_eq!(shaped, vec![(2, 0), (3, 0), (2, 1), (3, 1)]);
}

#[test]
fn hot_texel_spreads_to_its_bilinear_neighbourhood_only() {
    let (w, h) = (8u32, 4u32);
    let mut texels = vec![Vec4::ZERO; (w * h) as usize];
    texels[(w + 3) as usize] = Vec4::new(1.0, 1.0, 1.0, 1.0);
    let t = build(
        &Texture::new("hot", w, h, texels),
        Vec3::ONE,
        DomeConvention::Illum,
    );
    assert_eq!(t.marginal.len(), 5);
    assert_eq!(t.conditional.len(), 4 * 9);
    let mut sum = 0.0;
    for j in 0..h {
        for i in 0..w {
            let p = t.texel_probability(i, j);
            let near = (i as i32 - 3).abs() <= 1 && (j as i32 - 1).abs() <= 1;
            assert_eq!(p > 0.0, near, "texel ({i}, {j}): {p}");
            sum += p;
        }
    }
    assert!((sum - 1.0).abs() < 1e-6, "{sum}");
}

#[test]
fn black_map_falls_back_to_solid_angle() {
    let t = build(
        &Texture::new("black", 4, 2, vec![Vec4::ZERO; 8]),
        Vec3::ONE,
        DomeConvention::Illum,
    );
    assert_eq!(t.marginal, vec![0.0, 0.5, 1.0]);
    assert!((t.texel_probability(2, 1) - 0.125).abs() < 1e-7);
}

#[test]
fn guides_bracket_the_full_search() {
    // A peaked map with empty rows and cells: every u's full-search index lies in its bucket.
    let (w, h) = (16u32, 8u32);
    let texels = (0..w * h)
        .map(|k| {
            let (i, j) = (k % w, k / w);
            let v = if j == 3 {
                0.0
            } else if i == 5 && j == 2 {
                1e5
            } else {
                (i % 3) as f32
            };
            Vec4::new(v, v, v, 1.0)
        })
        .collect();
    let t = build(
        &Texture::new("peak", w, h, texels),
        Vec3::ONE,
        DomeConvention::Illum,
    );
    let check = |cdf: &[f32], guides: &[[u32; 2]]| {
        let n = cdf.len() - 1;
        let m = guides.len();
        for s in 0..=100_000u32 {
            let u = (s as f32 / 100_000.0).min(0.999_999_94);
            let full = cdf[..n].partition_point(|&c| c <= u) - 1;
            let [lo, hi] = guides[((u * m as f32) as usize).min(m - 1)];
            assert!(
                lo as usize <= full && full < hi as usize,
                "u {u}: {full} not in [{lo}, {hi})"
            );
            assert!(cdf[lo as usize] <= u && u < cdf[hi as usize]);
        }
    };
    let (mb, rb) = (t.marginal_buckets as usize, w as usize);
    assert_eq!(mb, MARGINAL_GUIDE as usize * h as usize);
    assert_eq!(t.guides.len(), mb + h as usize * rb);
    check(&t.marginal, &t.guides[..mb]);
    for j in 0..h as usize {
        let row = &t.conditional[j * (w as usize + 1)..(j + 1) * (w as usize + 1)];
        let g0 = mb + j * rb;
        check(row, &t.guides[g0..g0 + rb]);
    }
}

/// The tables from each texel's weight taken on its own (nine texel reads a cell for the
/// bilinear filter, as `build` did before it kept rows of luminance): bit for bit the same,
/// on every convention and filter, repeating and clamped.
#[test]
fn the_row_by_row_build_equals_the_per_texel_weights() {
    use crate::scene::TextureWrap;
    let (tw, th) = (7u32, 5u32);
    let texels: Vec<Vec4> = (0..tw * th)
        .map(|k| {
            let x = (k.wrapping_mul(2_654_435_761) % 1000) as f32 / 100.0;
            Vec4::new(x, 0.5 * x + (k % 3) as f32, 1.0 / (1.0 + x), 1.0)
        })
        .collect();
    let tint = Vec3::new(1.0, 0.8, 0.6);
    for conv in [
        DomeConvention::Illum,
        DomeConvention::Mitsuba,
        DomeConvention::Pbrt,
    ] {
        for filter in [TextureFilter::Bilinear, TextureFilter::Nearest] {
            for wrap in [TextureWrap::Repeat, TextureWrap::Clamp] {
                let mut t = Texture::new("t", tw, th, texels.clone());
                t.filter = filter;
                t.wrap = [wrap, wrap];
                let table = build(&t, tint, conv);
                let lum = |i: i64, j: i64| {
                    luminance((tint * t.texel(i, j).truncate()).as_dvec3()).max(0.0)
                };
                let (w, h) = cells(conv, tw, th);
                let (w, h) = (w as usize, h as usize);
                let mut row_sums = Vec::new();
                let mut conditional = Vec::new();
                for j in 0..h {
                    let measure = match conv {
                        DomeConvention::Pbrt => 1.0,
                        _ => (std::f64::consts::PI * (j as f64 + 0.5) / h as f64).sin(),
                    };
                    let row: Vec<f64> = (0..w as i64)
                        .map(|i| {
                            let j = j as i64;
                            let l = match (conv, filter) {
                                (DomeConvention::Mitsuba, _) => {
                                    let wr = |x: i64| x.rem_euclid(tw as i64);
                                    0.25 * (lum(wr(i), j)
                                        + lum(wr(i + 1), j)
                                        + lum(wr(i), j + 1)
                                        + lum(wr(i + 1), j + 1))
                                }
                                (DomeConvention::Illum, TextureFilter::Bilinear) => {
                                    const K: [f64; 3] = [0.125, 0.75, 0.125];
                                    let mut s = 0.0;
                                    for (b, kb) in K.iter().enumerate() {
                                        for (a, ka) in K.iter().enumerate() {
                                            s += ka * kb * lum(i + a as i64 - 1, j + b as i64 - 1);
                                        }
                                    }
                                    s
                                }
                                _ => lum(i, j),
                            };
                            l * measure
                        })
                        .collect();
                    let sum: f64 = row.iter().sum();
                    row_sums.push(sum);
                    conditional.extend(cdf(&row, sum));
                }
                let grand: f64 = row_sums.iter().sum();
                let what = format!("{conv:?} {filter:?} {wrap:?}");
                assert_eq!(table.conditional, conditional, "{what}");
                assert_eq!(table.marginal, cdf(&row_sums, grand), "{what}");
                assert_eq!(table.integral, grand / (w * h) as f64, "{what}");
            }
        }
    }
}

/// The guides' linear sweep gives the indices of a binary search of each bucket's ends.
#[test]
fn the_guide_sweep_equals_the_binary_search() {
    let mut x = 12_345u64;
    let mut next = move || {
        x = x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
        (x >> 40) as f64 / (1u64 << 24) as f64
    };
    for n in [1usize, 2, 3, 17, 256, 1000] {
        // Weights with zero stretches and a peak: repeated CDF values, tiny and huge steps.
        let weights: Vec<f64> = (0..n)
            .map(|k| match k % 7 {
                0 | 1 => 0.0,
                3 => 1e6 * next(),
                _ => next(),
            })
            .collect();
        let sum = weights.iter().sum();
        let c = cdf(&weights, sum);
        let index = |x: f64| {
            let x = (x.max(0.0) as f32).min(0.999_999_94);
            c[..n].partition_point(|&v| v <= x).max(1) - 1
        };
        for factor in [1u32, 4, 16] {
            let m = n * factor as usize;
            let expected: Vec<[u32; 2]> = (0..m)
                .map(|k| {
                    let lo = index(k as f64 / m as f64 - 1e-6);
                    let hi = index((k + 1) as f64 / m as f64 + 1e-6) + 1;
                    [lo as u32, hi as u32]
                })
                .collect();
            assert_eq!(
                guide(&c, factor),
                expected,
                "n {n}, {factor} buckets an interval"
            );
        }
    }
}
