//! Statistics shared by the test-support modules.
#![allow(dead_code)]

/// Complementary error function, relative error < 1.2e-7 everywhere (Numerical Recipes `erfcc`,
/// Chebyshev fit); good enough for p-values down to 1e-30 and for the exact Smith Lambda.
pub fn erfc(x: f64) -> f64 {
    // Horner's scheme over the coefficients (a loop: rustfmt takes ~30 s on the nested form).
    const C: [f64; 10] = [
        -1.265_512_23,
        1.000_023_68,
        0.374_091_96,
        0.096_784_18,
        -0.186_288_06,
        0.278_868_07,
        -1.135_203_98,
        1.488_515_87,
        -0.822_152_23,
        0.170_872_77,
    ];
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = C.iter().rev().fold(0.0, |acc, &c| acc * t + c);
    let ans = t * (-z * z + poly).exp();
    if x >= 0.0 { ans } else { 2.0 - ans }
}

/// Two-sided normal quantile: the z with P(|Z| > z) = alpha.
pub fn z_for(alpha: f64) -> f64 {
    // P(|Z| > z) = erfc(z / sqrt 2); solve by bisection.
    let (mut lo, mut hi) = (0.0f64, 40.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if erfc(mid / std::f64::consts::SQRT_2) > alpha {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Two-sided quantile of Student's t with `dof` degrees of freedom for tail probability `alpha`
/// (Cornish-Fisher expansion around the normal quantile): the statistic of a mean divided by its
/// *estimated* standard error.
pub fn t_for(alpha: f64, dof: f64) -> f64 {
    let z = z_for(alpha);
    let (z3, z5) = (z.powi(3), z.powi(5));
    z + (z3 + z) / (4.0 * dof) + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * dof * dof)
}
