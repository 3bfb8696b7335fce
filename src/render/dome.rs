//! Importance-sampling tables of a dome (environment) light's equirectangular map, read by
//! `sample_dome`/`dome_hit` in glsl/shared/light_sampling.glsl (TECHNIQUES.md 2.4).
//!
//! Texel (i, j) (column i, row j from the top; u = longitude, v = θ/π with v = 0 at +Y) gets the
//! weight `w_ij = sin θ_j · Σ_ab k_a k_b lum(tint ⊙ L[j+b][i+a])`, k = (1/8, 3/4, 1/8): the luminance
//! integrated over the texel of the bilinear lookup that `texture_lookup` (glsl/shared/scene.glsl)
//! makes, wrapping in both directions as it does, times sin θ at the row centre. Every texel the
//! bilinear radiance reaches therefore has a positive weight, so the pdf is positive wherever the
//! dome's radiance is (needed when light sampling is used alone, as for the course's diffuse lobe).
//!
//! The tables are a marginal CDF over rows and one conditional CDF per row, accumulated in f64 and
//! stored as f32 with exact 0 and 1 ends. The GPU samples a row and a texel by binary search and a
//! uniform point inside the texel; its pdf is `P(row) P(texel | row) W H / (2π² sin θ)` with the
//! probabilities taken as differences of the stored CDFs — exactly the mass the search assigns.

use crate::layout::GpuDomeSampling;
use crate::scene::Texture;
use glam::Vec3;

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
}

/// Luminance weights of linear RGB (Rec. 709), as `luminance()` in glsl/shared/common.glsl.
pub fn luminance(c: Vec3) -> f64 {
    0.2126 * f64::from(c.x) + 0.7152 * f64::from(c.y) + 0.0722 * f64::from(c.z)
}

/// Builds the tables of `texture` as a dome map whose radiance is `tint ⊙ texel` (the tint is the
/// light's colour; only its relative channel weights matter).
pub fn build(texture: &Texture, tint: Vec3) -> DomeTable {
    let w = texture.width as usize;
    let h = texture.height as usize;
    assert!(
        w > 0 && h > 0 && texture.texels.len() == w * h,
        "dome texture {}: {}x{} with {} texels",
        texture.name,
        w,
        h,
        texture.texels.len()
    );
    let lum: Vec<f64> = texture
        .texels
        .iter()
        .map(|t| luminance(tint * t.truncate()).max(0.0))
        .collect();
    // Texel integral of the bilinear reconstruction: a separable (1/8, 3/4, 1/8) filter.
    const K: [f64; 3] = [0.125, 0.75, 0.125];
    let mut horizontal = vec![0.0f64; w * h];
    for j in 0..h {
        for i in 0..w {
            let mut s = 0.0;
            for (a, k) in K.iter().enumerate() {
                let ii = (i + w + a - 1) % w;
                s += k * lum[j * w + ii];
            }
            horizontal[j * w + i] = s;
        }
    }
    let mut weights = vec![0.0f64; w * h];
    for j in 0..h {
        let theta = std::f64::consts::PI * (j as f64 + 0.5) / h as f64;
        let sin_theta = theta.sin();
        for i in 0..w {
            let mut s = 0.0;
            for (b, k) in K.iter().enumerate() {
                let jj = (j + h + b - 1) % h;
                s += k * horizontal[jj * w + i];
            }
            weights[j * w + i] = s * sin_theta;
        }
    }
    let total: f64 = weights.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        // A black (or broken) map: sample by solid angle (sin θ) so that the pdf stays valid.
        for j in 0..h {
            let theta = std::f64::consts::PI * (j as f64 + 0.5) / h as f64;
            weights[j * w..(j + 1) * w].fill(theta.sin());
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
    DomeTable {
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

impl DomeTable {
    /// The data to upload as one buffer: the marginal CDF, then the conditional CDFs.
    pub fn data(&self) -> Vec<f32> {
        let mut v = Vec::with_capacity(self.marginal.len() + self.conditional.len());
        v.extend_from_slice(&self.marginal);
        v.extend_from_slice(&self.conditional);
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
            pad: 0,
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

    /// Solid-angle pdf of the sampler at lat-long coordinates (u, v) (f64, for tests and tools).
    pub fn pdf_uv(&self, u: f64, v: f64) -> f64 {
        let i = ((u * f64::from(self.width)) as u32).min(self.width - 1);
        let j = ((v * f64::from(self.height)) as u32).min(self.height - 1);
        let sin_theta = (std::f64::consts::PI * v).sin();
        if sin_theta <= 0.0 {
            return 0.0;
        }
        self.texel_probability(i, j) * f64::from(self.width) * f64::from(self.height)
            / (2.0 * std::f64::consts::PI * std::f64::consts::PI * sin_theta)
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
            &Texture {
                name: "hot".into(),
                width: w,
                height: h,
                texels,
            },
            Vec3::ONE,
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
            &Texture {
                name: "black".into(),
                width: 4,
                height: 2,
                texels: vec![Vec4::ZERO; 8],
            },
            Vec3::ONE,
        );
        assert_eq!(t.marginal, vec![0.0, 0.5, 1.0]);
        assert!((t.texel_probability(2, 1) - 0.125).abs() < 1e-7);
    }
}
