//! Image error metrics (docs/techniques.md, "Error metrics and the half-buffer estimate"),
//! computed per channel on linear values and averaged over pixels and channels:
//!
//! - MSE = mean (I - R)^2, RMSE = sqrt(MSE), MAE = mean |I - R|;
//! - relMSE = mean (I - R)^2 / (R^2 + ε) with ε = [`RELMSE_EPSILON`] = 0.01.
//!
//! Without a reference, [`estimated_relmse`] estimates the relMSE of an unbiased render from its
//! two half-buffers (even- and odd-numbered samples). It sees variance only: it cannot see bias.

/// ε of relMSE.
pub const RELMSE_EPSILON: f64 = 0.01;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorMetrics {
    pub rmse: f64,
    pub relmse: f64,
    pub mae: f64,
    /// Pixels of the image with a NaN or infinite channel (left out of the other metrics).
    pub non_finite_pixels: u64,
}

fn finite(p: &[f32; 3]) -> bool {
    p.iter().all(|c| c.is_finite())
}

/// Errors of `image` against `reference` (same length).
pub fn compare(image: &[[f32; 3]], reference: &[[f32; 3]]) -> ErrorMetrics {
    assert_eq!(
        image.len(),
        reference.len(),
        "image and reference sizes differ"
    );
    let (mut se, mut rel, mut ae, mut n, mut bad) = (0.0, 0.0, 0.0, 0u64, 0u64);
    for (i, r) in image.iter().zip(reference) {
        if !finite(i) {
            bad += 1;
            continue;
        }
        for c in 0..3 {
            let (x, y) = (f64::from(i[c]), f64::from(r[c]));
            let d = x - y;
            se += d * d;
            rel += d * d / (y * y + RELMSE_EPSILON);
            ae += d.abs();
        }
        n += 3;
    }
    let n = n.max(1) as f64;
    ErrorMetrics {
        rmse: (se / n).sqrt(),
        relmse: rel / n,
        mae: ae / n,
        non_finite_pixels: bad,
    }
}

/// Estimated relMSE of `image` (pixel i the mean of `counts[i]` samples) from the mean of its
/// even-numbered samples `even` (ceil(n/2) of them) and of its odd-numbered ones `odd`
/// (floor(n/2)), at the pixels whose samples alternate between two independent sequences
/// (`split`, crate::film::Split).
///
/// With σ² the per-sample variance, Var(even - odd) = σ² (1/n_e + 1/n_o) and Var(image) = σ²/n,
/// so (even - odd)² / (n (1/n_e + 1/n_o)) is an unbiased estimate of the pixel's squared error
/// when the renderer is unbiased. The unknown reference in the relMSE denominator is replaced by
/// the image itself, which biases the estimate up by about 3·Var(pixel)/pixel² (the curvature of
/// 1/x²); that bias vanishes as samples accumulate. Where only some pixels split (witness
/// blocks, crate::film::Split), the others' error comes from their sample variance `variance`
/// (s²/n, the error of independent samples, which stratification lowers by a gain that varies
/// across the image): the split pixels measure that gain, Σ term / Σ s²/n over them, and the
/// image's estimate is the gain times the mean of s²/n over every pixel (a ratio estimator:
/// consistent as witnesses accumulate, and far steadier than the witnesses' own mean where the
/// error gathers in a few places). Each pixel's s²/n is of its own count, so the witnesses'
/// lower error (twice the samples) is in the estimate. Where every pixel splits, the mean of
/// their terms. Pixels of fewer than 2 samples are left out; None when every pixel has fewer, or
/// a pixel that does not split has.
pub fn estimated_relmse(
    image: &[[f32; 3]],
    even: &[[f32; 3]],
    odd: &[[f32; 3]],
    counts: &[u32],
    split: &[bool],
    variance: &[[f32; 3]],
) -> Option<f64> {
    let terms = estimated_relmse_pixels(image, even, odd, counts, split);
    // A pixel's s²/n relative to its value. At a witness (2N samples, N of each sequence) that of
    // one sequence's N samples, as every other pixel has it, halved: from the sum of squares
    // (n mean² + (n - 1) n s²/n) and the halves' means, (Σx²/2 - N (even² + odd²)/2) / (N (N - 1))
    // has the expectation of s²/N of one sequence (s² of stratified samples is not σ², but it is
    // the same at every pixel that takes N samples of one sequence).
    let relative = |i: usize, witness: bool| {
        let (x, v, n) = (image[i], variance[i], f64::from(counts[i]));
        (0..3)
            .map(|c| {
                let (x, v) = (f64::from(x[c]), f64::from(v[c]));
                let m = if witness {
                    let half = (n / 2.0).floor();
                    let squares = n * x * x + (n - 1.0) * n * v;
                    let (e, o) = (f64::from(even[i][c]), f64::from(odd[i][c]));
                    (squares / 2.0 - half * (e * e + o * o) / 2.0).max(0.0)
                        / (half * (half - 1.0)).max(1.0)
                        / 2.0
                } else {
                    v
                };
                m / (x * x + RELMSE_EPSILON)
            })
            .sum::<f64>()
            / 3.0
    };
    let witnesses = !split.iter().all(|&s| s);
    let (mut sum, mut count) = (0.0, 0u64);
    let (mut witness_mc, mut all_mc, mut all) = (0.0, 0.0, 0u64);
    for (i, &t) in terms.iter().enumerate() {
        let w = witnesses && split[i];
        if !t.is_nan() {
            sum += t;
            count += 1;
            if witnesses {
                witness_mc += relative(i, w);
            }
        }
        if witnesses
            && counts[i] >= if w { 4 } else { 2 }
            && finite(&image[i])
            && finite(&variance[i])
        {
            all_mc += relative(i, w);
            all += 1;
        }
    }
    // At one sample a pixel the other pixels have no s² yet: no estimate, as where every pixel
    // splits.
    let unmeasured = (0..counts.len()).any(|i| !split[i] && counts[i] < 2);
    if count == 0 || unmeasured {
        return None;
    }
    if split.iter().all(|&s| s) || witness_mc.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
    {
        return Some(sum / count as f64);
    }
    Some(sum / witness_mc * all_mc / all.max(1) as f64)
}

/// Each split pixel's term of [`estimated_relmse`] (its channels' mean), NaN for a pixel left out
/// (not split, or fewer than 2 samples): what two renders of the same pixels are compared by,
/// pixel against pixel.
pub fn estimated_relmse_pixels(
    image: &[[f32; 3]],
    even: &[[f32; 3]],
    odd: &[[f32; 3]],
    counts: &[u32],
    split: &[bool],
) -> Vec<f64> {
    image
        .iter()
        .zip(even)
        .zip(odd)
        .zip(counts)
        .zip(split)
        .map(|((((i, e), o), &n), &s)| {
            if !s || n < 2 || !(finite(i) && finite(e) && finite(o)) {
                return f64::NAN;
            }
            let ne = f64::from(n.div_ceil(2));
            let no = f64::from(n / 2);
            let scale = 1.0 / (f64::from(n) * (1.0 / ne + 1.0 / no));
            let mut pixel = 0.0;
            for c in 0..3 {
                let d = f64::from(e[c]) - f64::from(o[c]);
                let x = f64::from(i[c]);
                pixel += d * d * scale / (x * x + RELMSE_EPSILON);
            }
            pixel / 3.0
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_have_zero_error() {
        let a = vec![[0.5f32, 2.0, 0.0]; 10];
        assert_eq!(compare(&a, &a), ErrorMetrics::default());
    }

    #[test]
    fn known_perturbation_matches_closed_forms() {
        // Reference r = 1 everywhere, image = r + 0.1 on half the pixels, - 0.3 on the others.
        let r = vec![[1.0f32; 3]; 8];
        let img: Vec<[f32; 3]> = (0..8)
            .map(|i| if i % 2 == 0 { [1.1; 3] } else { [0.7; 3] })
            .collect();
        let m = compare(&img, &r);
        let d1 = 1.1f32 as f64 - 1.0;
        let d2 = 0.7f32 as f64 - 1.0;
        let mse = (d1 * d1 + d2 * d2) / 2.0;
        assert!((m.rmse - mse.sqrt()).abs() < 1e-12);
        assert!((m.relmse - mse / (1.0 + RELMSE_EPSILON)).abs() < 1e-12);
        assert!((m.mae - (d1.abs() + d2.abs()) / 2.0).abs() < 1e-12);
        assert_eq!(m.non_finite_pixels, 0);
    }

    #[test]
    fn non_finite_pixels_are_counted_and_left_out() {
        let r = vec![[1.0f32; 3]; 4];
        let mut img = r.clone();
        img[1] = [f32::NAN, 1.0, 1.0];
        img[2] = [1.0, f32::INFINITY, 1.0];
        let m = compare(&img, &r);
        assert_eq!(m.non_finite_pixels, 2);
        assert_eq!(m.rmse, 0.0);
    }

    #[test]
    fn half_buffer_estimate_is_unbiased_for_gaussian_noise() {
        // Pixels of true value 1 with per-sample noise σ = 0.5, n = 8 samples: the expected
        // squared error of the mean is σ²/n; the estimate must agree within its own spread.
        let (n, pixels, sigma) = (8u32, 20000usize, 0.5f64);
        let mut state = 12345u64;
        let mut gauss = || {
            // Box-Muller from a 64-bit LCG.
            let mut u = || {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
            };
            let (a, b) = (u(), u());
            (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
        };
        let (mut img, mut even, mut odd) = (vec![], vec![], vec![]);
        let mut true_se = 0.0;
        for _ in 0..pixels {
            let s: Vec<f64> = (0..n).map(|_| 1.0 + sigma * gauss()).collect();
            let e = s.iter().step_by(2).sum::<f64>() / 4.0;
            let o = s.iter().skip(1).step_by(2).sum::<f64>() / 4.0;
            let m = s.iter().sum::<f64>() / 8.0;
            true_se += (m - 1.0) * (m - 1.0);
            img.push([m as f32; 3]);
            even.push([e as f32; 3]);
            odd.push([o as f32; 3]);
        }
        // With the same (image-based) denominators, the estimate's expectation is exactly
        // mean(σ²/n / (x² + ε)); the per-pixel estimate is a scaled χ²(1), relative spread
        // sqrt(2 / pixels). 5 standard deviations.
        let expected: f64 = img
            .iter()
            .map(|p| sigma * sigma / f64::from(n) / (f64::from(p[0]).powi(2) + RELMSE_EPSILON))
            .sum::<f64>()
            / pixels as f64;
        let counts = vec![n; pixels];
        let split = vec![true; pixels];
        let variance = vec![[0.0f32; 3]; pixels];
        let est = estimated_relmse(&img, &even, &odd, &counts, &split, &variance).unwrap();
        let tol = 5.0 * (2.0 / pixels as f64).sqrt() * expected;
        assert!(
            (est - expected).abs() < tol,
            "estimate {est}, expected {expected} ± {tol}"
        );
        // Against the true relMSE (reference denominators) it is biased by about 3σ²/n, the
        // curvature of 1/x²: 9% at this noise level, vanishing as samples accumulate.
        let truth = true_se / pixels as f64 / (1.0 + RELMSE_EPSILON);
        let bias = 3.0 * sigma * sigma / f64::from(n);
        assert!(
            (est / truth - 1.0 - bias).abs() < 0.05,
            "estimate {est}, true {truth}"
        );
        let one = vec![1; pixels];
        assert_eq!(
            estimated_relmse(&img, &even, &odd, &one, &split, &variance),
            None
        );
    }
}
