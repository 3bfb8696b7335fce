//! Analytic unshadowed irradiance of the lights (glsl/lights/irradiance.glsl through
//! tests/kernels/irradiance_check.comp, the control variates' closed forms) against float64
//! references validated by Monte Carlo (z-tests) and the values of docs/techniques.md; and the
//! accurate inverse trigonometry of glsl/shared/common.glsl that those formulas and the light
//! samplers use (tests/kernels/trig_check.comp).

mod common;

use common::lights::*;
use common::*;
use glam::DVec3;
use illum::layout::*;
use illum::stress::closed_form::{polygon_irradiance, sphere_irradiance};
use std::f64::consts::PI;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct IrradianceCase {
    light: GpuLight,
    p: [f32; 4],
    n: [f32; 4],
}

fn regular_polygon(c: DVec3, nd: DVec3, td: DVec3, r: f64, sides: usize) -> Vec<DVec3> {
    let bd = nd.cross(td);
    let rn = r * (2.0 * PI / (sides as f64 * (2.0 * PI / sides as f64).sin())).sqrt();
    (0..sides)
        .map(|k| {
            let phi = 2.0 * PI * k as f64 / sides as f64;
            c + rn * (phi.cos() * td + phi.sin() * bd)
        })
        .collect()
}

/// float64 reference of light_irradiance(): exact for spheres, suns and polygons; disks as a
/// 4096-gon of equal area (error ~1e-7).
fn irradiance_ref(l: &GpuLight, p: DVec3, n: DVec3) -> f64 {
    let two = l.flags & LIGHT_FLAG_TWO_SIDED != 0;
    let facing = |c: DVec3, nl: DVec3| {
        let s = (p - c).dot(nl);
        s > 0.0 || (s < 0.0 && two)
    };
    match l.kind {
        LIGHT_SPHERE => {
            let (c, r) = (d3(l.p0), f64::from(l.p0[3]));
            let dc = c - p;
            if dc.length() <= r {
                return if two { PI } else { 0.0 };
            }
            sphere_irradiance(n.dot(dc.normalize()), r * r / dc.length_squared())
        }
        LIGHT_SUN => {
            let om = f64::from(l.p1[0]);
            let s = d3(l.p0);
            if om <= 0.0 {
                return n.dot(s).max(0.0);
            }
            let s2 = om * (2.0 - om);
            sphere_irradiance(n.dot(s) / s.length(), s2) / (PI * s2)
        }
        LIGHT_RECT => {
            let (c, eu, ev) = (d3(l.p0), d3(l.p1), d3(l.p2));
            if !facing(c, eu.cross(ev)) {
                return 0.0;
            }
            let a = c - 0.5 * eu - 0.5 * ev - p;
            polygon_irradiance(n, &[a, a + eu, a + eu + ev, a + ev])
        }
        LIGHT_TRIANGLE => {
            let (v0, e1, e2) = (d3(l.p0), d3(l.p1), d3(l.p2));
            if !facing(v0, e1.cross(e2)) {
                return 0.0;
            }
            let a = v0 - p;
            polygon_irradiance(n, &[a, a + e1, a + e2])
        }
        LIGHT_DISK => {
            let (c, r, nd, td) = (d3(l.p0), f64::from(l.p0[3]), d3(l.p1), d3(l.p2));
            if !facing(c, nd) {
                return 0.0;
            }
            let v: Vec<DVec3> = regular_polygon(c - p, nd, td, r, 4096);
            polygon_irradiance(n, &v)
        }
        _ => 0.0,
    }
}

/// Monte Carlo E/L with cosine-weighted directions about n: pi P(the direction meets the light's
/// emitting side). Returns the estimate and its standard error.
fn irradiance_mc(l: &GpuLight, p: DVec3, n: DVec3, samples: usize, rng: &mut Rng) -> (f64, f64) {
    let (t, b) = basis(n);
    let mut hits = 0usize;
    let mut ambiguous = 0usize;
    for _ in 0..samples {
        let (u1, u2) = (rng.uniform(), rng.uniform());
        let r = u1.sqrt();
        let phi = 2.0 * PI * u2;
        let d = r * phi.cos() * t + r * phi.sin() * b + (1.0 - u1).max(0.0).sqrt() * n;
        match meets(l, p, d) {
            Some(true) => hits += 1,
            Some(false) => {}
            None => ambiguous += 1,
        }
    }
    // Directions within 1e-4 of an edge count half (their measure is negligible).
    let p_hit = (hits as f64 + 0.5 * ambiguous as f64) / samples as f64;
    (
        PI * p_hit,
        PI * (p_hit * (1.0 - p_hit) / samples as f64).sqrt(),
    )
}

#[test]
fn irradiance_matches_references() {
    let ctx = context();
    let k = Kernel::new(
        &ctx,
        "irradiance_check",
        illum_test_kernels::IRRADIANCE_CHECK_PLAIN,
    );
    let z = DVec3::Z;
    let o = DVec3::ZERO;
    // (name, light, p, n, value from docs/techniques.md, "Reference values", if listed there)
    let mut cases: Vec<(String, GpuLight, DVec3, DVec3, Option<f64>)> = Vec::new();
    let sphere_table = [
        (3.0, [0.34907, 0.17453, 0.06522, 0.02557, 0.00461]),
        (1.5, [1.39626, 0.71055, 0.36910, 0.23282, 0.12664]),
        (10.0, [0.03142, 0.01571, 0.00546, 0.00067, 0.00000]),
    ];
    for (d, values) in sphere_table {
        for (theta, value) in [0.0f64, 60.0, 80.0, 90.0, 100.0].iter().zip(values) {
            let th = theta.to_radians();
            let c = d * DVec3::new(th.sin(), 0.0, th.cos());
            cases.push((
                format!("sphere d/r {d} at {theta}°"),
                sphere(c, 1.0, false),
                o,
                z,
                Some(value),
            ));
        }
    }
    // Rects of "Reference values" (half-extents 1 x 0.5, tilted about x), oriented to face p.
    for ((cx, cy, cz), tilt, value) in [
        ((0.0, 0.0, 2.0), 0.0f64, 0.41584),
        ((1.0, 0.5, 1.0), 30.0, 0.38187),
        ((2.0, 0.0, 0.3), 70.0, 0.00762),
        ((0.0, 0.0, 0.0), 90.0, 0.0),
    ] {
        let t = tilt.to_radians();
        let ex = DVec3::new(2.0, 0.0, 0.0);
        let ey = DVec3::new(0.0, t.cos(), t.sin());
        let c = DVec3::new(cx, cy, cz);
        // Emitting toward p: normal ey x ex or ex x ey, whichever faces the origin.
        let l = if (o - c).dot(ey.cross(ex)) > 0.0 {
            rect(c, ey, ex, false)
        } else {
            rect(c, ex, ey, false)
        };
        cases.push((format!("rect at {c} tilt {tilt}°"), l, o, z, Some(value)));
    }
    // Disks of "Reference values": disk at the origin facing +z, point at (a, 0, h), normal n.
    for (h, a, r, nrm, value) in [
        (1.0, 0.0, 0.5, DVec3::new(0.0, 0.0, -1.0), 0.62832),
        (1.0, 1.0, 0.5, DVec3::new(0.0, 0.0, -1.0), 0.20696),
        (0.5, 2.0, 1.0, DVec3::new(-0.6, 0.0, -0.8), 0.18374),
        (1.0, 0.7, 0.5, DVec3::new(0.3, -0.2, -0.933), 0.26255),
    ] {
        let c = DVec3::new(-a, 0.0, -h);
        cases.push((
            format!("disk h {h} a {a} R {r}"),
            disk(c, z, r, false),
            o,
            nrm.normalize(),
            Some(value),
        ));
    }
    // Horizon crossings and other configurations without a listed value.
    let extra: Vec<(&str, GpuLight, DVec3)> = vec![
        (
            "rect crossing the horizon",
            rect(
                DVec3::new(0.3, 0.0, 0.2),
                DVec3::new(0.0, 1.0, 0.0),
                DVec3::new(0.6, 0.0, -0.8),
                false,
            ),
            z,
        ),
        (
            "rect crossing, tilted normal",
            rect(
                DVec3::new(1.0, 0.2, 0.5),
                DVec3::new(1.0, 0.0, 1.0),
                DVec3::new(0.0, 2.0, 0.0),
                false,
            ),
            DVec3::new(-0.5, 0.2, 1.0).normalize(),
        ),
        (
            "rect below the horizon",
            rect(
                DVec3::new(0.0, 0.0, -2.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
                false,
            ),
            z,
        ),
        (
            "rect seen from behind",
            rect(
                DVec3::new(0.0, 0.0, 2.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
                false,
            ),
            z,
        ),
        (
            "rect two-sided from behind",
            rect(
                DVec3::new(0.0, 0.0, 2.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
                true,
            ),
            z,
        ),
        (
            "tiny rect (point approximation)",
            rect(
                DVec3::new(0.7, 0.3, 1.4),
                DVec3::new(1e-3, 0.0, 0.0),
                DVec3::new(0.0, -1e-3, 0.0),
                false,
            ),
            z,
        ),
        (
            "tiny tilted triangle (point approximation)",
            triangle(
                DVec3::new(-0.5, 0.3, 1.0),
                DVec3::new(0.0, 2e-3, 0.0),
                DVec3::new(2e-3, 0.0, 1e-3),
                false,
            ),
            DVec3::new(0.2, 0.0, 1.0).normalize(),
        ),
        (
            "triangle",
            triangle(
                DVec3::new(-1.0, -0.5, 2.0),
                DVec3::new(0.5, 1.5, -0.2),
                DVec3::new(2.0, 0.0, 0.3),
                false,
            ),
            z,
        ),
        (
            "triangle crossing the horizon",
            triangle(
                DVec3::new(-0.5, -0.5, -0.3),
                DVec3::new(0.0, 1.0, 0.8),
                DVec3::new(1.5, 0.0, 0.6),
                false,
            ),
            z,
        ),
        (
            "disk crossing the horizon",
            disk(
                DVec3::new(0.8, 0.0, 0.2),
                DVec3::new(-1.0, 0.0, -0.3),
                0.5,
                false,
            ),
            z,
        ),
        (
            "disk crossing, steep",
            disk(
                DVec3::new(0.5, 0.5, 0.1),
                DVec3::new(-1.0, -1.0, 0.2),
                0.6,
                false,
            ),
            z,
        ),
        (
            "disk crossing, two-sided back",
            disk(
                DVec3::new(0.4, 0.0, 0.3),
                DVec3::new(1.0, 0.0, 0.5),
                0.5,
                true,
            ),
            z,
        ),
        (
            "disk below the horizon",
            disk(
                DVec3::new(0.0, 0.0, -1.0),
                DVec3::new(0.0, 0.0, 1.0),
                0.5,
                false,
            ),
            z,
        ),
        (
            "disk grazing above",
            disk(
                DVec3::new(1.0, 0.0, 0.6),
                DVec3::new(-1.0, 0.0, 0.1),
                0.5,
                false,
            ),
            z,
        ),
        (
            "sphere tiny (r/d 1e-3)",
            sphere(DVec3::new(3.0, 0.0, 10.0), 0.01, false),
            z,
        ),
        (
            "sphere crossing, close",
            sphere(DVec3::new(1.2, 0.0, 0.3), 1.0, false),
            z,
        ),
        (
            "sphere inside, two-sided",
            sphere(DVec3::new(0.1, 0.0, 0.2), 1.0, true),
            z,
        ),
        (
            "sphere inside, one-sided",
            sphere(DVec3::new(0.1, 0.0, 0.2), 1.0, false),
            z,
        ),
    ];
    for (name, l, n) in extra {
        cases.push((name.to_string(), l, o, n, None));
    }
    for (half, theta) in [
        (0.2666, 0.0),
        (0.2666, 60.0),
        (0.2666, 89.9),
        (0.2666, 90.1),
        (10.0, 85.0),
        (10.0, 90.0),
        (10.0, 97.0),
        (0.0, 30.0),
    ] {
        let th = f64::to_radians(theta);
        let l = sun(DVec3::new(th.sin(), 0.0, th.cos()), half);
        cases.push((format!("sun {half}° at {theta}°"), l, o, z, None));
    }

    let input: Vec<IrradianceCase> = cases
        .iter()
        .map(|(_, l, p, n, _)| IrradianceCase {
            light: *l,
            p: f4(*p, 0.0),
            n: f4(*n, 0.0),
        })
        .collect();
    let out: Vec<[f32; 4]> = k.run(&[0u32; 4], &input, 0, input.len(), 0, input.len());
    let mut rng = Rng::new(2024);
    for ((name, l, p, n, listed), got) in cases.iter().zip(&out) {
        // The reference from the float32 light and the float32 normal the GPU saw.
        let n32 = d3(f4(*n, 0.0));
        let reference = irradiance_ref(l, *p, n32);
        let got = f64::from(got[0]);
        // The GPU formula against float64: float32 rounding through acos/atan and the rational edge
        // fit (relative 1e-4), plus the 32-gon's O(1/N^2) error for disks across the horizon.
        let mut tol = 1e-4 * reference.abs() + 1e-7;
        if l.kind == LIGHT_DISK {
            let (c, r, nd, td) = (d3(l.p0), f64::from(l.p0[3]), d3(l.p1), d3(l.p2));
            let reach = r * (1.0 - n32.dot(nd).powi(2)).max(0.0).sqrt();
            if n32.dot(c - *p).abs() < reach && reference > 0.0 {
                // Across the horizon the GPU clips a 32-gon of equal area (its error is O(1/N^2)).
                let ngon = polygon_irradiance(n32, &regular_polygon(c - *p, nd, td, r, 32));
                let approx = (ngon - reference).abs();
                eprintln!(
                    "{name}: 32-gon error {approx:.2e} ({:.2e} relative)",
                    approx / reference
                );
                assert!(approx <= 2e-3 * reference, "{name}: 32-gon error {approx}");
                tol += approx;
            }
        }
        eprintln!("{name}: GPU {got:.6}, float64 {reference:.6}");
        assert!(
            (got - reference).abs() <= tol,
            "{name}: GPU {got} vs float64 {reference}"
        );
        if let Some(v) = listed {
            // Listed with 5 decimals in docs/techniques.md, "Reference values".
            assert!(
                (reference - v).abs() <= 5.01e-6,
                "{name}: float64 {reference} vs listed {v}"
            );
        }
        // The float64 references against Monte Carlo (independent of every formula).
        if l.kind != LIGHT_SUN {
            let (m, e) = irradiance_mc(l, *p, n32, 400_000, &mut rng);
            let e = e.max(PI / 400_000.0); // no hit at all: sd of a count of 0 < 1
            z_test(
                &format!("{name}: Monte Carlo vs float64"),
                m,
                e,
                reference,
                0.0,
            );
        }
    }
    assert_no_validation_messages(&ctx);
}

// ---------------------------------------------------------------------------------------------
// Inverse trigonometry

/// atan2_accurate / acos_accurate / asin_accurate against float64 over their whole range, including
/// tiny angles: a few ulp (float32 epsilon 1.2e-7), where drivers' own atan/acos may be 2e-5 to
/// 1.6e-4 off (lavapipe, measured).
#[test]
fn inverse_trigonometry_is_accurate() {
    let ctx = context();
    let k = Kernel::new(&ctx, "trig_check", illum_test_kernels::TRIG_CHECK_PLAIN);
    let n = 1 << 18;
    let input: Vec<[f32; 4]> = (0..n)
        .map(|i| {
            let t = (i as f64 + 0.5) / n as f64;
            let y = 10f64.powf(-6.0 + 6.0 * t) * if i % 2 == 0 { 1.0 } else { -1.0 };
            let x = (1.0 - 2.0 * t) * 3.0;
            let c = 2.0 * t - 1.0;
            let w = 10f64.powf(-6.0 + 8.0 * t);
            [y as f32, x as f32, c as f32, w as f32]
        })
        .collect();
    let out: Vec<[f32; 4]> = k.run(&[0u32; 4], &input, 0, n, 0, n);
    let mut worst = [0.0f64; 4];
    for (q, o) in input.iter().zip(&out) {
        let q = q.map(f64::from);
        let o = o.map(f64::from);
        let r = [q[0].atan2(q[1]), q[2].acos(), q[3].atan(), q[2].asin()];
        for c in 0..4 {
            // Relative error, or absolute near zero for acos/asin (|result| >= 1e-3 otherwise).
            let scale = if c == 0 || c == 2 {
                r[c].abs()
            } else {
                r[c].abs().max(1e-3)
            };
            worst[c] = worst[c].max((o[c] - r[c]).abs() / scale);
        }
    }
    eprintln!(
        "worst relative errors: atan2 {:.1e}, acos {:.1e}, atan {:.1e}, asin {:.1e}",
        worst[0], worst[1], worst[2], worst[3]
    );
    assert!(worst.iter().all(|&e| e < 5e-7), "{worst:?}");
    assert_no_validation_messages(&ctx);
}

/// floor_int, floor_uint and ceil_uint (texel and table indices, sample counts) against f64's
/// floor and ceil: exact over |x| <= 2^22 (integers, their neighbours a float step away, and
/// uniform values), and clamped to [-2^22, 2^22] (floor_uint and ceil_uint: [0, 2^22]) for
/// larger, infinite and NaN inputs, so an index made from them stays in range.
#[test]
fn float_to_int_is_exact_in_range_and_clamped_outside() {
    let ctx = context();
    let k = Kernel::new(&ctx, "floor_check", illum_test_kernels::FLOOR_CHECK_PLAIN);
    const LIMIT: f64 = 4_194_304.0; // 2^22
    let mut input: Vec<f32> = Vec::new();
    for e in 0..=22 {
        for s in [-1.0f32, 1.0] {
            let v = s * (1u32 << e) as f32;
            input.extend([v, v.next_up(), v.next_down(), v + 0.5, v - 0.5]);
        }
    }
    let n = 1 << 16;
    input.extend((0..n).map(|i| ((i as f64 + 0.37) / n as f64 * 2.0 * LIMIT - LIMIT) as f32));
    input.extend((0..n).map(|i| ((i as f64 + 0.5) / n as f64 * 20.0 - 10.0) as f32));
    input.extend([
        0.0,
        -0.0,
        1e-30,
        -1e-30,
        5e6,
        -5e6,
        3e9,
        -3e9,
        f32::MAX,
        f32::MIN,
    ]);
    input.extend([f32::INFINITY, f32::NEG_INFINITY, f32::NAN, -f32::NAN]);
    let out: Vec<[u32; 4]> = k.run(&[0u32; 4], &input, 0, input.len(), 0, input.len());
    for (&x, o) in input.iter().zip(&out) {
        let (fi, fu, cu) = (o[0] as i32, o[1], o[2]);
        assert!(
            (-LIMIT..=LIMIT).contains(&f64::from(fi)),
            "floor_int({x}) = {fi}"
        );
        assert!(
            f64::from(fu) <= LIMIT && f64::from(cu) <= LIMIT,
            "{x}: {fu} {cu}"
        );
        let xd = f64::from(x);
        if xd.abs() <= LIMIT {
            assert_eq!(f64::from(fi), xd.floor(), "floor_int({x})");
            assert_eq!(f64::from(fu), xd.floor().max(0.0), "floor_uint({x})");
            assert_eq!(f64::from(cu), xd.ceil().max(0.0), "ceil_uint({x})");
        }
    }
    assert_no_validation_messages(&ctx);
}
