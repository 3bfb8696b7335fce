//! Chi-square goodness of fit of a direction sampler against its own pdf() (the pbrt-v4 /
//! Mitsuba 3 way), and the significance of the sampler tests (sampling_*.rs, brdf.rs).
//!
//! * The sphere (or the sampler's support) is parametrised by a 2D domain (x, y) ∈ [0,1]² with a
//!   known Jacobian dω/(dx dy): a polar grid about an axis, a cone, a light's surface, or the dome's
//!   texels. Each cell's probability is the integral of the GPU pdf() over the cell, by a 9×9
//!   midpoint rule (27×27 where the pdf is zero on part of the cell: an edge of the support), with
//!   the nested 3×3 (resp. 9×9) rule as an error estimate.
//! * Shape: the valid samples are binned and compared with the cell probabilities normalised to
//!   the number of valid samples; cells with expected count < 5 are pooled; p-value from the
//!   chi-square distribution with (categories - 1) degrees of freedom.
//! * Normalisation: the fraction of valid samples must equal the integral of pdf() (1 for lights),
//!   a z-test whose variance is the binomial variance plus the square of the quadrature error
//!   estimate.
//! * Every valid sample must have pdf() > 0 at its own direction (the sampler never goes where the
//!   pdf is zero; cells that the quadrature finds empty but that hold samples are pooled).
//! * Significance 0.01 for the whole suite, split over [`HYPOTHESES`] tests with Šidák's correction.

use super::{Domain, chi2_sf, normal_two_sided_p};
use glam::DVec3;

/// Upper bound on the number of hypothesis tests (chi-square and z-tests) in tests/sampling_*.rs
/// and tests/brdf.rs together (about 290 today); Šidák's correction with an upper bound is
/// conservative.
pub const HYPOTHESES: f64 = 400.0;
/// Family-wise significance level of the suite.
pub const SIGNIFICANCE: f64 = 0.01;

/// Per-test significance after Šidák's correction.
pub fn alpha() -> f64 {
    1.0 - (1.0 - SIGNIFICANCE).powf(1.0 / HYPOTHESES)
}

/// Two-sided z-test of an estimate with standard error `err` against `expected` (whose own
/// uncertainty `ref_err` adds in quadrature). Panics with `what` when rejected at [`alpha`].
pub fn z_test(what: &str, estimate: f64, err: f64, expected: f64, ref_err: f64) {
    let sigma = (err * err + ref_err * ref_err).sqrt();
    let z = (estimate - expected) / sigma;
    let p = normal_two_sided_p(z);
    eprintln!("{what}: {estimate:.6} ± {err:.2e} vs {expected:.6} (z = {z:+.2}, p = {p:.3e})");
    assert!(
        p > alpha() || !z.is_finite() && estimate == expected,
        "{what}: {estimate} ± {err} differs from {expected} (z = {z:.2}, p = {p:.3e} < {:.3e})",
        alpha()
    );
}

/// Outcome of [`sampler_test`], for reporting.
#[derive(Debug)]
pub struct Chi2Report {
    pub chi2: f64,
    pub dof: usize,
    pub p: f64,
    pub integral: f64,
    pub integral_err: f64,
}

/// The k×k midpoint sub-points of cell (ix, iy).
fn cell_points(d: &Domain, ix: usize, iy: usize, k: usize) -> Vec<Option<(DVec3, f64)>> {
    let mut v = Vec::with_capacity(k * k);
    for b in 0..k {
        for a in 0..k {
            let x = (ix as f64 + (a as f64 + 0.5) / k as f64) / d.nx as f64;
            let y = (iy as f64 + (b as f64 + 0.5) / k as f64) / d.ny as f64;
            v.push((d.to_dir)(x, y));
        }
    }
    v
}

/// Integrates pdf × Jacobian over every cell: (integral, error estimate) per cell. Midpoint rule
/// on 9×9 sub-points, refined to 27×27 and 81×81 where the pdf is zero on part of the cell (an edge
/// of the support) or where the error estimate (half the difference to the nested 3× coarser rule)
/// is not small against the sd of the cell's count among `samples` draws.
fn integrate_cells(
    d: &Domain,
    samples: f64,
    pdf: &mut dyn FnMut(&[[f32; 4]]) -> Vec<f64>,
) -> (Vec<f64>, Vec<f64>) {
    let cells = d.nx * d.ny;
    let cell_area = 1.0 / cells as f64;
    let mut integral = vec![0.0; cells];
    let mut error = vec![0.0; cells];
    let mut list: Vec<usize> = (0..cells).collect();
    let mut k = 9;
    loop {
        // Evaluate in chunks of at most 2^20 directions.
        let per_chunk = ((1usize << 20) / (k * k)).max(1);
        let mut next = Vec::new();
        for chunk in list.chunks(per_chunk) {
            let mut dirs = Vec::with_capacity(chunk.len() * k * k);
            let mut jac = Vec::with_capacity(chunk.len() * k * k);
            for &c in chunk {
                for p in cell_points(d, c % d.nx, c / d.nx, k) {
                    let (dir, j) = p.unwrap_or((DVec3::Z, 0.0));
                    dirs.push([dir.x as f32, dir.y as f32, dir.z as f32, 0.0]);
                    jac.push(j);
                }
            }
            let values = pdf(&dirs);
            for (r, &c) in chunk.iter().enumerate() {
                let s: Vec<f64> = (0..k * k)
                    .map(|q| values[r * k * k + q] * jac[r * k * k + q])
                    .collect();
                let fine: f64 = s.iter().sum::<f64>() / (k * k) as f64;
                // The nested rule with a third of the points per axis: sub-points (3a+1, 3b+1).
                let kc = k / 3;
                let mut coarse = 0.0;
                for b in 0..kc {
                    for a in 0..kc {
                        coarse += s[(3 * b + 1) * k + 3 * a + 1];
                    }
                }
                coarse /= (kc * kc) as f64;
                integral[c] = fine * cell_area;
                error[c] = 0.5 * (fine - coarse).abs() * cell_area;
                let zeros = s.iter().filter(|&&x| x == 0.0).count();
                let count = integral[c] * samples;
                if (zeros > 0 && zeros < k * k) || error[c] * samples > 0.1 * count.max(1.0).sqrt()
                {
                    next.push(c);
                }
            }
        }
        if next.is_empty() || k >= 81 {
            break;
        }
        list = next;
        k *= 3;
    }
    (integral, error)
}

/// Chi-square test of a sampler against its pdf: `valid` are the directions of the valid samples
/// out of `total` samples drawn; `pdf` evaluates the GPU pdf() for directions (xyz of each entry).
pub fn sampler_test(
    name: &str,
    valid: &[DVec3],
    total: usize,
    domain: &Domain,
    pdf: &mut dyn FnMut(&[[f32; 4]]) -> Vec<f64>,
) -> Chi2Report {
    let cells = domain.nx * domain.ny;
    let (integral, error) = integrate_cells(domain, total as f64, pdf);
    let sum: f64 = integral.iter().sum();
    let err: f64 = error.iter().sum();

    let mut observed = vec![0.0f64; cells];
    let mut outside = 0usize;
    for &d in valid {
        match (domain.from_dir)(d) {
            Some((x, y)) => {
                let ix = ((x * domain.nx as f64) as usize).min(domain.nx - 1);
                let iy = ((y * domain.ny as f64) as usize).min(domain.ny - 1);
                observed[iy * domain.nx + ix] += 1.0;
            }
            None => outside += 1,
        }
    }
    assert_eq!(
        outside, 0,
        "{name}: {outside} valid samples outside the domain of the test (where the pdf is 0)"
    );

    // Normalisation: P(valid) = integral of the pdf. Besides the binomial variance and the
    // quadrature error, pdf() is float32: its values carry a few ulp of relative error (1e-6).
    let n = total as f64;
    let frac = valid.len() as f64 / n;
    let var = sum.clamp(0.0, 1.0) * (1.0 - sum.clamp(0.0, 1.0)) / n;
    let float_err = 1e-6 * sum;
    let z = (frac - sum) / (var + err * err + float_err * float_err).sqrt();
    let p_norm = normal_two_sided_p(z);
    assert!(
        p_norm > alpha(),
        "{name}: valid fraction {frac:.6} but the pdf integrates to {sum:.6} ± {err:.2e} (z = {z:.2}, p = {p_norm:.2e})"
    );

    // Shape: expected counts normalised to the valid samples, pooled below 5.
    let nv = valid.len() as f64;
    let mut order: Vec<usize> = (0..cells).collect();
    let expected: Vec<f64> = integral.iter().map(|i| i / sum * nv).collect();
    order.sort_by(|&a, &b| expected[a].partial_cmp(&expected[b]).unwrap());
    let (mut chi2, mut dof) = (0.0f64, 0usize);
    let (mut pool_o, mut pool_e) = (0.0f64, 0.0f64);
    for &c in &order {
        let (o, e) = (observed[c], expected[c]);
        if e < 5.0 || (pool_e > 0.0 && pool_e < 5.0) {
            pool_o += o;
            pool_e += e;
        } else {
            chi2 += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pool_e > 0.0 {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        dof += 1;
    } else {
        assert!(
            pool_o == 0.0,
            "{name}: {pool_o} samples where the pdf integrates to 0"
        );
    }
    if std::env::var("ILLUM_CHI2_DEBUG").is_ok() {
        let mut worst: Vec<usize> = (0..cells).filter(|&c| expected[c] >= 5.0).collect();
        let dev = |c: usize| (observed[c] - expected[c]).powi(2) / expected[c];
        worst.sort_by(|&a, &b| dev(b).partial_cmp(&dev(a)).unwrap());
        for &c in worst.iter().take(12) {
            eprintln!(
                "  cell ({}, {}): observed {} expected {:.1} (quadrature error {:.2e})",
                c % domain.nx,
                c / domain.nx,
                observed[c],
                expected[c],
                error[c] / sum * nv
            );
        }
    }
    let dof = dof.saturating_sub(1).max(1);
    let p = chi2_sf(chi2, dof as f64);
    eprintln!(
        "{name}: chi2 = {chi2:.1}, dof = {dof}, p = {p:.3e}; valid {frac:.5}, pdf integral {sum:.5} ± {err:.1e}"
    );
    assert!(
        p > alpha(),
        "{name}: chi-square test rejects the sampler: chi2 = {chi2:.1} with {dof} dof, p = {p:.3e} < {:.3e}",
        alpha()
    );
    Chi2Report {
        chi2,
        dof,
        p,
        integral: sum,
        integral_err: err,
    }
}

/// Checks the pdf a sampler reported against pdf() re-evaluated at the sampled direction: every
/// valid sample must have pdf() > 0, and the two must agree to float precision (relative 1e-3
/// covers float32 rounding through different formulas, amplified by 1/cos at grazing angles), except
/// for samples that `ambiguous` says lie on a boundary where two float paths may pick different
/// cells.
pub fn check_reported_pdfs(
    name: &str,
    samples: &[(f64, f64)],
    ambiguous: impl Fn(usize) -> bool,
) -> usize {
    let mut mismatches = 0usize;
    for (i, &(reported, reeval)) in samples.iter().enumerate() {
        assert!(
            reeval > 0.0,
            "{name}: sample {i} has pdf {reported} but pdf() of its direction is {reeval}"
        );
        if (reported - reeval).abs() > 1e-3 * reported.max(reeval) {
            assert!(
                ambiguous(i),
                "{name}: sample {i}: sampler pdf {reported} vs pdf() {reeval}"
            );
            mismatches += 1;
        }
    }
    mismatches
}
