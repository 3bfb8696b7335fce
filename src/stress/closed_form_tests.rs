//! The irradiance closed forms (disk, sphere, polygon) against quadrature and known values.

use super::*;

/// The disk's vector irradiance against midpoint quadrature over the disk's area.
#[test]
fn disk_irradiance_matches_quadrature() {
    let cases = [
        (
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(0.0, 0.0, -1.0),
            20.0,
            DVec3::Z,
        ),
        (
            DVec3::new(0.7, 0.2, 1.5),
            DVec3::new(0.1, 0.0, -1.0).normalize(),
            0.8,
            DVec3::Z,
        ),
        (
            DVec3::new(3.0, 0.0, 0.5),
            DVec3::new(0.0, 0.0, -1.0),
            4.0,
            DVec3::new(0.3, 0.0, 1.0).normalize(),
        ),
    ];
    for (c, nd, r, n) in cases {
        let (t, b) = nd.any_orthonormal_pair();
        let (nr, nphi) = (4000, 400);
        let mut sum = 0.0;
        for i in 0..nr {
            let (r0, r1) = (r * i as f64 / nr as f64, r * (i + 1) as f64 / nr as f64);
            let rm = 0.5 * (r0 + r1);
            let da = 0.5 * (r1 * r1 - r0 * r0) * 2.0 * PI / nphi as f64;
            for k in 0..nphi {
                let phi = 2.0 * PI * (k as f64 + 0.5) / nphi as f64;
                let y = c + rm * (phi.cos() * t + phi.sin() * b);
                let d2 = y.length_squared();
                let w = y / d2.sqrt();
                sum += w.dot(n).max(0.0) * (-w.dot(nd)).max(0.0) / d2 * da;
            }
        }
        let got = disk_irradiance(c, nd, r, n, false).unwrap();
        assert!(
            (got - sum).abs() < 2e-4 * sum,
            "disk {c} r {r}: {got} vs quadrature {sum}"
        );
    }
    // Behind a one-sided disk: 0; crossing the horizon: an error.
    assert_eq!(
        disk_irradiance(DVec3::new(0.0, 0.0, 1.0), DVec3::Z, 1.0, DVec3::Z, false),
        Ok(0.0)
    );
    assert!(disk_irradiance(DVec3::new(0.0, 0.0, 0.1), -DVec3::Z, 1.0, DVec3::X, false).is_err());
}

/// Snyder's formula against brute-force quadrature over the cap, horizon crossing included.
#[test]
fn sphere_irradiance_matches_quadrature() {
    for &(sigma_deg, theta_deg) in &[(5.0, 30.0), (20.0, 80.0), (40.0, 95.0), (60.0, 60.0)] {
        let (sigma, theta): (f64, f64) = (f64::to_radians(sigma_deg), f64::to_radians(theta_deg));
        let axis = DVec3::new(theta.sin(), 0.0, theta.cos());
        let (t, b) = axis.any_orthonormal_pair();
        let n = 2000;
        let mut sum = 0.0;
        for i in 0..n {
            let om = (1.0 - sigma.cos()) * (i as f64 + 0.5) / n as f64;
            let ct = 1.0 - om;
            let st = (1.0 - ct * ct).sqrt();
            for k in 0..n {
                let phi = 2.0 * PI * (k as f64 + 0.5) / n as f64;
                let w = axis * ct + (t * phi.cos() + b * phi.sin()) * st;
                sum += w.z.max(0.0);
            }
        }
        let quad = sum * 2.0 * PI * (1.0 - sigma.cos()) / (n * n) as f64;
        let exact = sphere_irradiance(theta.cos(), sigma.sin().powi(2));
        assert!(
            (exact - quad).abs() < 1e-5 * quad.max(1e-3),
            "{sigma_deg} {theta_deg}: {exact} vs {quad}"
        );
    }
}

/// The polygon formula gives the sphere-cap-free known values: a unit square at height 1
/// centred above the point, and a tiny square whose E/L tends to A cos / d².
#[test]
fn polygon_irradiance_known_values() {
    let sq = |h: f64, a: f64| {
        [
            DVec3::new(-a, -a, h),
            DVec3::new(-a, a, h),
            DVec3::new(a, a, h),
            DVec3::new(a, -a, h),
        ]
    };
    // Square of half-side a at height h, centred: E/L = 4 q atan(q), q = X / sqrt(1 + X²),
    // X = a / h (four corner rectangles of the parallel-rectangle view factor).
    let (a, h): (f64, f64) = (1.0, 1.0);
    let x = a / h;
    let q = x / (1.0 + x * x).sqrt();
    let ff = 4.0 * q * q.atan();
    let e = emitter_irradiance(&sq(h, a), DVec3::ZERO, DVec3::Z, false);
    assert!((e - ff).abs() < 1e-12, "{e} vs {ff}");
    let tiny = emitter_irradiance(&sq(1e5, 5e3), DVec3::ZERO, DVec3::Z, true);
    let approx = 1e8 / 1e10; // A / d² (cos = 1)
    assert!((tiny / approx - 1.0).abs() < 5e-3, "{tiny}");
    // Behind a one-sided emitter whose normal points up (+z): nothing.
    let mut up = sq(1.0, 1.0);
    up.reverse();
    assert_eq!(emitter_irradiance(&up, DVec3::ZERO, DVec3::Z, false), 0.0);
    let two = emitter_irradiance(&up, DVec3::ZERO, DVec3::Z, true);
    assert!((two - ff).abs() < 1e-12);
}
