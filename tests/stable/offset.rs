//! offset_ray_origin far from the origin (part of tests/stable.rs; its helpers come from `super`).

use super::*;

#[test]
fn offset_ray_origin_avoids_self_intersection() {
    let ctx = context();
    let mut points = vec![
        DVec3::new(1e5, -1e5, 1e5),
        DVec3::new(123456.7, -98765.4, 100001.3),
        DVec3::new(-1e5, 0.7e5, -1.3e5),
        DVec3::new(1e5, 0.01, -3.0),
        DVec3::new(-3.0, 1e5, 0.01),
        DVec3::new(0.01, -3.0, -1e5),
        DVec3::new(1.5, -2.5, 7.25),
        DVec3::new(1e5, 0.0, 0.05),
        DVec3::new(-0.7e5, 0.04, 1e5),
        // Near the origin (|p_i| < 1/32: the float offset).
        DVec3::new(0.01, -0.02, 0.003),
        DVec3::ZERO,
        DVec3::new(0.03, -0.03, 1e-7),
    ];
    // Far along x and y, small z (1e-3 to 0.3, either branch): with a nearly horizontal plane the
    // rounding of the large coordinates, projected on the normal, competes with the offset of z.
    let frac = |x: f64| x - x.floor();
    points.extend((0..64).map(|k| {
        let k = f64::from(k);
        DVec3::new(
            1e5 * (0.5 + frac(0.618_034 * k)),
            1e4 * (frac(0.414_214 * k) - 0.5),
            1e-3 * 300f64.powf(frac(0.732_051 * k)) * if k % 2.0 == 0.0 { 1.0 } else { -1.0 },
        )
    }));
    let normals = [
        DVec3::X,
        DVec3::Y,
        DVec3::Z,
        DVec3::new(1.0, 2.0, 3.0).normalize(),
        DVec3::new(-2.0, 0.5, 1.0).normalize(),
        DVec3::new(0.0, 0.6, 0.8),
        DVec3::new(0.003, 0.0, 1.0).normalize(),
        DVec3::new(0.01, -0.02, 1.0).normalize(),
        DVec3::new(-0.001, 0.002, 1.0).normalize(),
    ];
    // Directions leaving the surface: n.d from 1 down to grazing 1e-4, several azimuths.
    let elevations: [f64; 5] = [1.0, 0.5, 1e-2, 1e-3, 1e-4];
    let azimuths: [f64; 4] = [0.0, 1.3, 2.9, 4.4];

    struct Case {
        what: String,
        p: DVec3,
        plane_point: DVec3,
        normal: DVec3,
    }
    let mut recs = Vec::new();
    let mut cases = Vec::new();
    for &p0 in &points {
        let size = (p0.abs().max_element() * 1e-3).clamp(0.01, 100.0);
        for &n in &normals {
            let (t, b) = basis(n);
            let (u, v) = (r32(size * t), r32(size * b));
            let n_rect = u.cross(v).normalize();
            let n_disk = r32(n);
            for side in [1.0, -1.0] {
                // Shapes centred at the hit point (p exactly on the plane) and elsewhere (p the
                // float32 rounding of a point of the plane).
                let p_c = r32(p0);
                let c_off = r32(p0 - 0.3 * u + 0.2 * v);
                let p_off = r32(c_off + 0.3 * u - 0.2 * v);
                let dc_off = r32(p0 - 0.3 * u);
                let dp_off = r32(dc_off + 0.3 * u);
                for &(shape, p, centre, normal) in &[
                    ("rect at p", p_c, p_c, n_rect),
                    ("rect elsewhere", p_off, c_off, n_rect),
                    ("disk at p", p_c, p_c, n_disk.normalize()),
                    ("disk elsewhere", dp_off, dc_off, n_disk.normalize()),
                ] {
                    for &ce in &elevations {
                        for &phi in &azimuths {
                            let se = (1.0f64 - ce * ce).sqrt();
                            let dir =
                                r32(side * ce * normal + se * (phi.cos() * t + phi.sin() * b));
                            let rec = if shape.starts_with("rect") {
                                record(
                                    f4(p, side),
                                    f4(centre, 0.0),
                                    f4(u, 0.0),
                                    f4(v, 0.0),
                                    dir,
                                    CASE_OFFSET_RECT,
                                )
                            } else {
                                record(
                                    f4(p, side),
                                    f4(centre, 0.5 * size),
                                    f4(n_disk, 0.0),
                                    [0.0; 4],
                                    dir,
                                    CASE_OFFSET_DISK,
                                )
                            };
                            recs.push(rec);
                            cases.push(Case {
                                what: format!(
                                    "{shape}, p {p0}, n {n:.4}, side {side}, n.d {ce}, phi {phi}"
                                ),
                                p,
                                plane_point: centre,
                                normal: side * normal,
                            });
                        }
                    }
                }
            }
        }
    }
    let out = run(&ctx, &recs);
    let (mut worst_rel, mut worst_abs_near) = (0.0f64, 0.0f64);
    let mut min_side = f64::INFINITY;
    let mut rehits = Vec::new();
    for (c, o) in cases.iter().zip(&out) {
        let origin = d3(o[0]);
        let t = o[0][3];
        // Strictly on the normal's side of the plane through the f32 input point p, and of the
        // shape's own plane.
        let h_p = (origin - c.p).dot(c.normal);
        let h_shape = (origin - c.plane_point).dot(c.normal);
        assert!(
            h_p > 0.0,
            "{}: offset origin {origin} is {h_p:e} from the plane through p",
            c.what
        );
        min_side = min_side.min(h_shape / h_p);
        if h_shape <= 0.0 || t != f32::INFINITY {
            rehits.push(format!(
                "{}: origin {h_shape:e} from the shape's plane, t = {t}",
                c.what
            ));
        }
        let moved = (origin - c.p).length();
        if c.p.abs().max_element() < 1.0 / 32.0 {
            worst_abs_near = worst_abs_near.max(moved);
        } else {
            worst_rel = worst_rel.max(moved / c.p.length());
        }
    }
    eprintln!(
        "offset_ray_origin, {} cases: max offset {worst_rel:.2e} |p| (|p_i| >= 1/32 somewhere), \
         {worst_abs_near:.2e} near the origin; distance to the shape's plane at least {min_side:.3} x the offset along n; \
         {} re-hits",
        cases.len(),
        rehits.len()
    );
    assert!(
        rehits.is_empty(),
        "{} rays re-hit their own surface:\n{}",
        rehits.len(),
        rehits.join("\n")
    );
    // Before the fix in common.glsl (4 ulp at least per nonzero normal component) 480 of these
    // rays re-hit their surface, from up to 11 offsets on the wrong side of its plane; after it
    // the origins keep at least 0.88 of their offset.
    assert!(min_side > 0.5, "{min_side}");
    // 256 ulp per unit normal component: at most 256 * 2^-23 = 3.05e-5 |p_i| per component.
    assert!(worst_rel < 1e-4, "offset {worst_rel:.3e} |p|");
    // Near the origin: 1/65536 per unit normal component.
    assert!(worst_abs_near <= 1.6e-5, "offset {worst_abs_near:.3e}");
    assert_no_validation_messages(&ctx);
}
