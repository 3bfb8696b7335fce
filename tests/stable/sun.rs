//! The sun's cone sampler at tiny and large angles (part of tests/stable.rs; helpers from `super`).

use super::*;

#[test]
fn sun_cone_is_stable() {
    let ctx = context();
    let dirs = [
        DVec3::Z,
        DVec3::new(1.0, 2.0, 3.0).normalize(),
        DVec3::NEG_Y,
    ];
    let us = [(0.999_999_9, 0.1), (0.5, 0.6), (1e-3, 0.9)];
    let mut recs = Vec::new();
    let mut cases = Vec::new();
    let mut worst_naive_om = 0.0f64;
    for theta_deg in log_space(1e-4, 15.0, 49) {
        let theta = theta_deg.to_radians();
        // What src/gpu_scene/mod.rs stores: 1 - cos(theta) = 2 sin^2(theta / 2) in f64, then f32.
        // The naive f32 1 - cos(theta) is 0 (a delta sun) below ~0.02 degree.
        let om = s32(2.0 * (0.5 * theta).sin().powi(2));
        let exact = 2.0 * (0.5 * theta).sin().powi(2);
        worst_naive_om = worst_naive_om.max(rel(f64::from(1.0 - (theta as f32).cos()), exact));
        assert!(rel(om, exact) < 1e-7);
        for &d in &dirs {
            let d = r32(d);
            for &(ux, uy) in &us {
                recs.push(record(
                    f4(d, om),
                    [ux as f32, uy as f32, 0.0, 0.0],
                    [0.0; 4],
                    [0.0; 4],
                    DVec3::ZERO,
                    CASE_SUN,
                ));
                cases.push((theta_deg, d, om, ux));
            }
        }
    }
    let out = run(&ctx, &recs);
    let (mut worst_axis, mut worst_generic, mut worst_pdf) = (0.0f64, 0.0f64, 0.0f64);
    for (&(theta_deg, d, om, ux), o) in cases.iter().zip(&out) {
        let wi = d3(o[0]);
        let (pdf, hit_pdf, delta) = (f64::from(o[0][3]), f64::from(o[1][0]), o[1][1]);
        assert!(delta == 0.0, "{theta_deg} deg: delta sun");
        let truth_pdf = 1.0 / (2.0 * PI * om);
        worst_pdf = worst_pdf
            .max(rel(pdf, truth_pdf))
            .max(rel(hit_pdf, truth_pdf));
        assert!(
            hit_pdf > 0.0,
            "{theta_deg} deg: light_pdf of the sampled direction is {hit_pdf}"
        );
        // The sample's angle from the sun: 1 - cos = u om, theta = 2 asin(sqrt(u om / 2)).
        let expected = 2.0 * (0.5 * ux * om).sqrt().asin();
        let dn = d.normalize();
        let angle = wi.cross(dn).length().atan2(wi.dot(dn));
        let err = (angle - expected).abs();
        if d == DVec3::Z {
            // About +z the tangent components keep full relative precision: relative error.
            worst_axis = worst_axis.max(err / expected);
        } else {
            // Elsewhere a float32 direction resolves angles to ~6e-8 rad: absolute error.
            worst_generic = worst_generic.max(err);
        }
    }
    eprintln!(
        "sun cone, theta_s in [1e-4, 15] deg: sampled angle relative error {worst_axis:.2e} about +z, \
         absolute {worst_generic:.2e} rad elsewhere; pdf relative error {worst_pdf:.2e}; \
         naive f32 1 - cos(theta_s): {worst_naive_om:.2e}"
    );
    // Measured 1.5e-7, 5.5e-8 rad and 9e-8 on lavapipe; sin(theta) = sqrt(1 - cos^2) would give
    // angle 0 (100% error) for every sample below ~0.02 degree.
    assert!(worst_axis < 6e-7, "{worst_axis:.3e}");
    assert!(worst_generic < 2e-7, "{worst_generic:.3e}");
    assert!(worst_pdf < 4e-7, "{worst_pdf:.3e}");
    assert!(worst_naive_om >= 1.0, "the naive formula should fail here");
    assert_no_validation_messages(&ctx);
}
