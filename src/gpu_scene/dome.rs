//! Importance-sampling tables of a dome (environment) light's map, read by `sample_dome`/`dome_hit`
//! in glsl/lights/infinite_lights.glsl (docs/techniques.md, "Dome importance sampling"), for each
//! map convention of glsl/lights/dome_map.glsl.
//!
//! The tables cover a grid of cells in map coordinates (u, v), and a cell's weight is the luminance
//! `lum(tint ⊙ L)` the convention's lookup gives inside it, times the solid angle per unit map
//! area at its centre (sin θ for lat-long maps, 1 for the equal-area square):
//! - illum: the cells are the texels; with the bilinear filter the weight is the texel integral
//!   of the bilinear lookup, a separable (1/8, 3/4, 1/8) tent over the neighbours as the texture's
//!   wrap modes reach them; with the nearest filter, the texel itself.
//! - Mitsuba: the cells lie between texel centres (W columns offset by half a texel, H − 1 rows
//!   from pole to pole), where the lookup is one bilinear patch: the mean of its four corners.
//! - pbrt: the cells are the texels of the square (nearest lookup).
//!
//! Every cell where the radiance can be positive therefore has a positive weight, so the pdf is
//! positive wherever the dome's radiance is (needed when light sampling is used alone, as for the
//! course's diffuse lobe).
//!
//! The tables are a marginal CDF over rows and one conditional CDF per row, accumulated in f64 and
//! stored as f32 with exact 0 and 1 ends. The GPU samples a row and a cell by binary search and a
//! uniform point inside the cell. Each CDF of n intervals has a guide of n buckets: bucket k holds
//! the index range `[lo, hi)` of the intervals that u in [k/n, (k+1)/n) (widened by 1e-6, more than
//! the GPU's rounding of `u n`) can fall in, so the search runs over a few intervals instead of n
//! (O(1) expected steps) and still returns the index of the full search; its pdf is `P(row) P(cell | row) W H / (dω/du dv)` with the
//! probabilities taken as differences of the stored CDFs — exactly the mass the search assigns.

use crate::layout::GpuDomeSampling;
use crate::scene::{DomeConvention, Texture, TextureFilter};
use glam::{DVec3, Vec3};

/// Host side of [`GpuDomeSampling`]: the CDF tables of one map.
#[derive(Clone, Debug)]
pub struct DomeTable {
    pub width: u32,
    pub height: u32,
    /// `height + 1` entries: 0, then the cumulative row probabilities, ending at exactly 1.
    pub marginal: Vec<f32>,
    /// `height` rows of `width + 1` entries, each 0 … 1 (a row of zero weight is uniform).
    pub conditional: Vec<f32>,
    /// Mean texel weight (before normalisation).
    pub integral: f64,
    /// Search guides: `height` buckets of the marginal, then `width` per row of the conditionals,
    /// each the `[lo, hi)` range of intervals a sample in that bucket can fall in.
    pub guides: Vec<[u32; 2]>,
    /// The dome's radiance on SH9 in world directions (src/gpu_scene/dome_sh.rs), set by the
    /// caller: the control variates' L_SH.
    pub sh: [[f32; 4]; 9],
}

/// Luminance weights of linear RGB (Rec. 709), as `luminance()` in glsl/shared/common.glsl.
pub fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// The cell grid of a map of `width` x `height` texels under `convention`: (columns, rows).
pub fn cells(convention: DomeConvention, width: u32, height: u32) -> (u32, u32) {
    match convention {
        DomeConvention::Mitsuba => (width, height.saturating_sub(1).max(1)),
        DomeConvention::Illum | DomeConvention::Pbrt => (width, height),
    }
}

/// Builds the tables of `texture` as a dome map whose radiance is `tint ⊙ texel` (the tint is the
/// light's colour; only its relative channel weights matter), laid out as `convention` says.
pub fn build(texture: &Texture, tint: Vec3, convention: DomeConvention) -> DomeTable {
    let (tw, th) = (texture.width as usize, texture.height as usize);
    assert!(
        tw > 0 && th > 0 && texture.texels.len() == tw * th,
        "dome texture {}: {}x{} with {} texels",
        texture.name,
        tw,
        th,
        texture.texels.len()
    );
    let lum =
        |i: i64, j: i64| luminance((tint * texture.texel(i, j).truncate()).as_dvec3()).max(0.0);
    let (cw, ch) = cells(convention, texture.width, texture.height);
    let (w, h) = (cw as usize, ch as usize);
    // Solid angle per unit map area at the centre of row j (up to a constant factor).
    let row_measure = |j: usize| match convention {
        DomeConvention::Pbrt => 1.0,
        _ => (std::f64::consts::PI * (j as f64 + 0.5) / h as f64).sin(),
    };
    let mut weights = vec![0.0f64; w * h];
    for j in 0..h {
        for i in 0..w {
            let (ii, jj) = (i as i64, j as i64);
            let l = match (convention, texture.filter) {
                (DomeConvention::Mitsuba, _) => {
                    // Between column centres i, i + 1 (periodic) and rows j, j + 1.
                    let wrap = |x: i64| x.rem_euclid(tw as i64);
                    0.25 * (lum(wrap(ii), jj)
                        + lum(wrap(ii + 1), jj)
                        + lum(wrap(ii), jj + 1)
                        + lum(wrap(ii + 1), jj + 1))
                }
                (DomeConvention::Pbrt, _) | (DomeConvention::Illum, TextureFilter::Nearest) => {
                    lum(ii, jj)
                }
                (DomeConvention::Illum, TextureFilter::Bilinear) => {
                    // Texel integral of the bilinear reconstruction, wrapped as the lookup wraps.
                    const K: [f64; 3] = [0.125, 0.75, 0.125];
                    let mut s = 0.0;
                    for (b, kb) in K.iter().enumerate() {
                        for (a, ka) in K.iter().enumerate() {
                            s += ka * kb * lum(ii + a as i64 - 1, jj + b as i64 - 1);
                        }
                    }
                    s
                }
            };
            weights[j * w + i] = l * row_measure(j);
        }
    }
    let total: f64 = weights.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        // A black (or broken) map: sample by solid angle so that the pdf stays valid.
        for j in 0..h {
            weights[j * w..(j + 1) * w].fill(row_measure(j));
        }
    }
    let mut conditional = Vec::with_capacity(h * (w + 1));
    let mut row_sums = Vec::with_capacity(h);
    for j in 0..h {
        let row = &weights[j * w..(j + 1) * w];
        let sum: f64 = row.iter().sum();
        row_sums.push(sum);
        conditional.extend(cdf(row, sum));
    }
    let grand: f64 = row_sums.iter().sum();
    let marginal = cdf(&row_sums, grand);
    let mut guides = guide(&marginal);
    for row in conditional.chunks(w + 1) {
        guides.extend(guide(row));
    }
    DomeTable {
        guides,
        sh: [[0.0; 4]; 9],
        width: w as u32,
        height: h as u32,
        marginal,
        conditional,
        integral: grand / (w * h) as f64,
    }
}

/// CDF of non-negative weights with exact ends; all-zero weights give a uniform CDF.
fn cdf(weights: &[f64], sum: f64) -> Vec<f32> {
    let n = weights.len();
    let mut out = Vec::with_capacity(n + 1);
    out.push(0.0f32);
    let mut acc = 0.0f64;
    for (k, &x) in weights.iter().enumerate() {
        acc += x;
        let c = if sum > 0.0 {
            acc / sum
        } else {
            (k + 1) as f64 / n as f64
        };
        out.push(c.min(1.0) as f32);
    }
    out[n] = 1.0;
    out
}

/// Search guide of a CDF of n intervals (n + 1 entries, see `cdf`): for bucket k of u in
/// [k/n, (k+1)/n), widened by `GUIDE_MARGIN` on both sides, the range `[lo, hi)` of the index i
/// with `cdf[i] <= u < cdf[i + 1]` (the GPU's `cdf_find`; monotone in u, so the ends suffice).
fn guide(cdf: &[f32]) -> Vec<[u32; 2]> {
    const GUIDE_MARGIN: f64 = 1e-6;
    const U_MAX: f32 = 0.999_999_94; // the GPU clamps u to this
    let n = cdf.len() - 1;
    let index = |x: f64| {
        let x = (x.max(0.0) as f32).min(U_MAX);
        cdf[..n].partition_point(|&c| c <= x).max(1) - 1
    };
    (0..n)
        .map(|k| {
            let lo = index(k as f64 / n as f64 - GUIDE_MARGIN);
            let hi = index((k + 1) as f64 / n as f64 + GUIDE_MARGIN) + 1;
            [lo as u32, hi as u32]
        })
        .collect()
}

impl DomeTable {
    /// The data to upload as one buffer: the marginal CDF, the conditional CDFs, then the guides
    /// (as u32 bit patterns).
    pub fn data(&self) -> Vec<f32> {
        let mut v = Vec::with_capacity(
            self.marginal.len() + self.conditional.len() + 2 * self.guides.len(),
        );
        v.extend_from_slice(&self.marginal);
        v.extend_from_slice(&self.conditional);
        v.extend(self.guides.iter().flatten().map(|&g| f32::from_bits(g)));
        v
    }

    /// The GPU descriptor of the tables uploaded as [`DomeTable::data`] at device address `address`.
    pub fn gpu(&self, address: u64) -> GpuDomeSampling {
        GpuDomeSampling {
            marginal: address,
            conditional: address + 4 * self.marginal.len() as u64,
            width: self.width,
            height: self.height,
            integral: self.integral as f32,
            defensive: 0.0,
            sh: self.sh,
        }
    }

    /// The probability the sampler gives texel (i, j): the same CDF differences the GPU takes.
    pub fn texel_probability(&self, i: u32, j: u32) -> f64 {
        let (i, j) = (i as usize, j as usize);
        let row = j * (self.width as usize + 1);
        let pm = self.marginal[j + 1] - self.marginal[j];
        let pc = self.conditional[row + i + 1] - self.conditional[row + i];
        f64::from(pm) * f64::from(pc)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec4;

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
            for s in 0..=100_000u32 {
                let u = (s as f32 / 100_000.0).min(0.999_999_94);
                let full = cdf[..n].partition_point(|&c| c <= u) - 1;
                let [lo, hi] = guides[((u * n as f32) as usize).min(n - 1)];
                assert!(
                    lo as usize <= full && full < hi as usize,
                    "u {u}: {full} not in [{lo}, {hi})"
                );
                assert!(cdf[lo as usize] <= u && u < cdf[hi as usize]);
            }
        };
        check(&t.marginal, &t.guides[..h as usize]);
        for j in 0..h as usize {
            let row = &t.conditional[j * (w as usize + 1)..(j + 1) * (w as usize + 1)];
            let g0 = h as usize + j * w as usize;
            check(row, &t.guides[g0..g0 + w as usize]);
        }
    }
}
