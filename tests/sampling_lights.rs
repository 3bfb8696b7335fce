//! The light samplers of glsl/lights/light_sampling.glsl on the GPU (tests/kernels/sample_light.comp)
//! for rects, spheres, disks, triangles and suns: chi-square tests of each against its own pdf()
//! and pdf consistency per sample (the harness is tests/common/lights.rs), pdf() integrating to
//! the probability of a sample and zero off the light; and the MIS weights of
//! glsl/direct/mis.glsl (tests/kernels/mis_check.comp) at extreme pdfs.

mod common;

use common::lights::*;
use common::*;
use glam::DVec3;
use illum::layout::*;
use std::f64::consts::PI;

// ---------------------------------------------------------------------------------------------
// Chi-square tests of the light samplers

#[test]
fn chi2_rect() {
    let g = Lights::new();
    let o = DVec3::ZERO;
    let cases = [
        // 2 x 1 facing the origin from 2 units: solid-angle sampling (Omega 0.43 sr).
        (
            "rect front",
            rect(
                DVec3::new(0.0, 0.0, 2.0),
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(0.0, -1.0, 0.0),
                false,
            ),
            o,
        ),
        // Tilted and off-axis.
        (
            "rect tilted",
            rect(
                DVec3::new(1.0, 0.5, 1.0),
                DVec3::new(1.5, 0.0, 0.0),
                DVec3::new(0.0, -0.7, -0.7),
                false,
            ),
            o,
        ),
        // Near: 5 cm above a 1 x 1 rect, off-centre (Omega 5.6 sr).
        (
            "rect near",
            rect(
                DVec3::new(-0.2, -0.1, 0.05),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, -1.0, 0.0),
                false,
            ),
            o,
        ),
        // Nearly enclosing (Omega > 6.22 sr): uniform hemisphere, misses are no sample.
        (
            "rect enclosing",
            rect(
                DVec3::new(0.0, 0.0, 0.004),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, -1.0, 0.0),
                false,
            ),
            o,
        ),
        // Far: Omega 4e-4 sr < 1e-3: area sampling.
        (
            "rect far",
            rect(
                DVec3::new(3.0, 2.0, 3.5),
                DVec3::new(0.1, 0.0, 0.0),
                DVec3::new(0.0, -0.1, 0.0),
                false,
            ),
            o,
        ),
        // Small but above the threshold: Omega 1.6e-3 sr.
        (
            "rect small",
            rect(
                DVec3::new(0.0, 0.0, 5.0),
                DVec3::new(0.2, 0.0, 0.0),
                DVec3::new(0.0, -0.2, 0.0),
                false,
            ),
            o,
        ),
        // Two-sided, seen from behind.
        (
            "rect two-sided back",
            rect(
                DVec3::new(0.3, 0.0, 1.5),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 0.5),
                true,
            ),
            o,
        ),
        // Grazing: the shading point 5 cm above the rect's plane, 1.5 to 2.5 units away.
        (
            "rect grazing",
            rect(
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
                false,
            ),
            DVec3::new(0.0, 0.0, 0.05),
        ),
    ];
    for (k, (name, l, p)) in cases.iter().enumerate() {
        let prm = params(*l, *p);
        g.check(name, &prm, &rect_domain(l, *p), 10 + k as u32, &never);
    }
    g.finish();
}

#[test]
fn chi2_sphere() {
    let g = Lights::new();
    let o = DVec3::ZERO;
    let cases: [(&str, GpuLight, DVec3, usize); 5] = [
        (
            "sphere d/r 3",
            sphere(DVec3::new(1.0, 2.0, 2.0), 1.0, false),
            o,
            32,
        ),
        (
            "sphere d/r 1.05",
            sphere(DVec3::new(0.0, 1.05, 0.0), 1.0, false),
            o,
            32,
        ),
        (
            "sphere r/d 1e-3",
            sphere(DVec3::new(0.0, 0.0, 10.0), 0.01, false),
            o,
            32,
        ),
        (
            "sphere r/d 1e-4",
            sphere(DVec3::new(0.0, 0.0, 10.0), 0.001, false),
            o,
            8,
        ),
        (
            "sphere two-sided, inside",
            sphere(DVec3::new(0.2, 0.1, -0.3), 1.0, true),
            o,
            32,
        ),
    ];
    for (k, (name, l, p, res)) in cases.iter().enumerate() {
        let prm = params(*l, *p);
        let (c, r) = (d3(l.p0), f64::from(l.p0[3]));
        let dc = c - *p;
        let domain = if dc.length() > r {
            let s2 = r * r / dc.length_squared();
            cone_domain(
                dc.normalize(),
                s2 / (1.0 + (1.0 - s2).sqrt()),
                *res,
                2 * res,
            )
        } else {
            sphere_inside_domain(l, *p)
        };
        g.check(name, &prm, &domain, 20 + k as u32, &never);
    }
    // A one-sided sphere seen from inside gives no sample, and pdf() is 0.
    let prm = params(sphere(DVec3::new(0.2, 0.1, -0.3), 1.0, false), o);
    let out = g.sample(&prm, 64, 1);
    assert!((0..64).all(|i| out.pdf(i) == 0.0));
    assert!(g.hit(&prm, &[[0.0, 0.0, 1.0, 0.0]])[0][0] == 0.0);
    g.finish();
}

#[test]
fn chi2_disk_triangle_sun() {
    let g = Lights::new();
    let o = DVec3::ZERO;
    let disks = [
        (
            "disk front",
            disk(
                DVec3::new(0.0, 0.0, 2.0),
                DVec3::new(0.0, 0.0, -1.0),
                1.0,
                false,
            ),
            o,
        ),
        (
            "disk tilted",
            disk(
                DVec3::new(1.5, 0.5, 1.0),
                DVec3::new(-1.0, 0.0, -1.0),
                0.6,
                false,
            ),
            o,
        ),
        (
            "disk grazing",
            disk(
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.05, 0.0, 1.0),
                0.5,
                false,
            ),
            DVec3::new(0.0, 0.0, 0.1),
        ),
        // A disk large for its distance (planar mixture of area and hemisphere sampling): above
        // its centre, and above its rim.
        (
            "disk huge near",
            disk(
                DVec3::new(0.0, 0.0, 0.5),
                DVec3::new(0.0, 0.0, -1.0),
                5.0,
                false,
            ),
            o,
        ),
        (
            "disk huge rim",
            disk(
                DVec3::new(4.0, 0.0, 0.5),
                DVec3::new(0.0, 0.0, -1.0),
                4.0,
                false,
            ),
            o,
        ),
        (
            "disk two-sided back",
            disk(
                DVec3::new(0.0, 0.5, 1.0),
                DVec3::new(0.0, 0.3, 1.0),
                0.4,
                true,
            ),
            o,
        ),
    ];
    for (k, (name, l, p)) in disks.iter().enumerate() {
        g.check(
            name,
            &params(*l, *p),
            &disk_domain(l, *p),
            30 + k as u32,
            &never,
        );
    }
    let tris = [
        (
            "triangle",
            triangle(
                DVec3::new(-1.0, -0.5, 2.0),
                DVec3::new(0.5, 1.5, -0.2),
                DVec3::new(2.0, 0.0, 0.3),
                false,
            ),
            o,
        ),
        (
            "triangle near",
            triangle(
                DVec3::new(-0.3, -0.3, 0.1),
                DVec3::new(0.0, 1.0, 0.0),
                DVec3::new(1.0, 0.2, 0.05),
                false,
            ),
            o,
        ),
        // Large for its distance (planar mixture), facing away from +z so p sees its front.
        (
            "triangle huge near",
            triangle(
                DVec3::new(-3.0, -3.0, 0.3),
                DVec3::new(0.0, 8.0, 0.0),
                DVec3::new(8.0, 0.0, 0.0),
                false,
            ),
            o,
        ),
    ];
    for (k, (name, l, p)) in tris.iter().enumerate() {
        g.check(
            name,
            &params(*l, *p),
            &triangle_domain(l, *p),
            40 + k as u32,
            &never,
        );
    }
    let suns = [
        ("sun 0.2666 deg", sun(DVec3::new(0.3, 0.4, 0.8), 0.2666)),
        ("sun 10 deg", sun(DVec3::new(-0.5, 0.1, 0.3), 10.0)),
    ];
    for (k, (name, l)) in suns.iter().enumerate() {
        let axis = d3(l.p0);
        g.check(
            name,
            &params(*l, o),
            &cone_domain(axis, f64::from(l.p1[0]), 32, 64),
            50 + k as u32,
            &never,
        );
    }
    // A delta sun: its direction, pdf 1 (probability), delta; light_pdf() is 0 for every direction.
    let prm = params(sun(DVec3::new(0.0, 0.6, 0.8), 0.0), o);
    let out = g.sample(&prm, 64, 2);
    for i in 0..64 {
        assert!(out.delta(i) && out.pdf(i) == 1.0);
        assert!((out.wi(i) - DVec3::new(0.0, 0.6, 0.8)).length() < 1e-6);
    }
    assert_eq!(g.hit(&prm, &[[0.0, 0.6, 0.8, 0.0]])[0][0], 0.0);
    // One-sided emitters seen from behind: no sample, pdf() 0.
    for (name, l) in [
        (
            "rect",
            rect(
                DVec3::new(0.0, 0.0, 2.0),
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
                false,
            ),
        ),
        (
            "disk",
            disk(
                DVec3::new(0.0, 0.0, 2.0),
                DVec3::new(0.0, 0.0, 1.0),
                1.0,
                false,
            ),
        ),
        (
            "triangle",
            triangle(
                DVec3::new(-1.0, -0.5, 2.0),
                DVec3::new(2.0, 0.0, 0.3),
                DVec3::new(0.5, 1.5, -0.2),
                false,
            ),
        ),
    ] {
        let prm = params(l, o);
        let out = g.sample(&prm, 256, 3);
        assert!((0..256).all(|i| out.pdf(i) == 0.0), "{name} from behind");
        assert_eq!(
            g.hit(&prm, &[[0.0, 0.0, 1.0, 0.0]])[0][0],
            0.0,
            "{name} from behind"
        );
    }
    g.finish();
}

/// Directions that miss a light get pdf() 0, and pdf() integrates over the sphere to the
/// probability that the sampler returns a sample (1, or less where a hemisphere direction can
/// miss): a z-test on uniformly distributed directions, for lights large enough that uniform
/// directions hit them often.
#[test]
fn pdf_integrates_to_one_and_is_zero_off_the_light() {
    let g = Lights::new();
    let o = DVec3::ZERO;
    let n = 1 << 20;
    let mut rng = Rng::new(77);
    let dirs: Vec<[f32; 4]> = (0..n).map(|_| f4(rng.sphere(), 0.0)).collect();
    // Each case's sampler: how much of it is area or solid-angle sampling (pdf integrates to 1)
    // and how much uniform sampling of the hemisphere facing a planar emitter (integrates to the
    // emitter's Omega / (2 pi): a miss is no sample; glsl/lights/light_sampling.glsl).
    const WHOLE: (f64, f64) = (1.0, 0.0);
    const HEMISPHERE: (f64, f64) = (0.0, 1.0);
    const MIXTURE: (f64, f64) = (0.5, 0.5);
    let cases = [
        (
            "rect",
            rect(
                DVec3::new(0.2, 0.0, 0.7),
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(0.0, -1.5, 0.0),
                false,
            ),
            WHOLE,
        ),
        (
            "rect (nearly enclosing: hemisphere)",
            rect(
                DVec3::new(0.0, 0.0, 0.004),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, -1.0, 0.0),
                false,
            ),
            HEMISPHERE,
        ),
        (
            "sphere",
            sphere(DVec3::new(0.0, 0.5, 1.5), 1.0, false),
            WHOLE,
        ),
        (
            "sphere inside",
            sphere(DVec3::new(0.2, 0.1, -0.3), 1.0, true),
            WHOLE,
        ),
        (
            "disk",
            disk(
                DVec3::new(0.0, 0.0, 0.8),
                DVec3::new(0.2, 0.0, -1.0),
                1.0,
                false,
            ),
            MIXTURE,
        ),
        (
            "disk two-sided",
            disk(
                DVec3::new(0.0, 0.0, 0.8),
                DVec3::new(0.2, 0.0, 1.0),
                1.0,
                true,
            ),
            MIXTURE,
        ),
        (
            "triangle",
            triangle(
                DVec3::new(-1.0, -1.0, 0.5),
                DVec3::new(0.0, 2.5, 0.0),
                DVec3::new(2.5, 0.0, 0.2),
                false,
            ),
            MIXTURE,
        ),
        ("sun 10 deg", sun(DVec3::new(0.3, 0.4, 0.8), 10.0), WHOLE),
    ];
    for (name, l, (whole, hemisphere)) in cases {
        let prm = params(l, o);
        let hits = g.hit(&prm, &dirs);
        let (m, e, _) = mean_and_error(hits.iter().map(|h| 4.0 * PI * f64::from(h[0])));
        // Omega / (2 pi) = twice the fraction of uniform directions that meet the emitter (host,
        // f64; directions within 1e-4 of an edge count as misses).
        let (frac, frac_err, _) = mean_and_error(
            dirs.iter()
                .map(|d| f64::from(u8::from(meets(&l, o, d3(*d)) == Some(true)))),
        );
        z_test(
            &format!("{name}: 4 pi E[pdf(uniform direction)]"),
            m,
            e,
            whole + hemisphere * 2.0 * frac,
            hemisphere * 2.0 * frac_err,
        );
        // pdf() > 0 exactly where the direction meets the emitter (checked on the host in f64,
        // away from the silhouette).
        let mut misses_with_pdf = 0;
        for (d, h) in dirs.iter().zip(&hits) {
            if let Some(inside) = meets(&l, o, d3(*d)) {
                if inside != (h[0] > 0.0) {
                    misses_with_pdf += 1;
                }
            }
        }
        assert_eq!(
            misses_with_pdf, 0,
            "{name}: pdf() disagrees with the geometry"
        );
    }
    g.finish();
}

// ---------------------------------------------------------------------------------------------
// MIS

#[test]
fn mis_weights_are_bounded_and_sum_to_one() {
    let ctx = context();
    let k = Kernel::new(&ctx, "mis_check", illum_test_kernels::MIS_CHECK_PLAIN);
    let counts = [0.0f32, 1.0, 4.0, 16.0];
    // The smallest normal float, not a subnormal: GPUs may flush subnormals to zero (Vulkan
    // allows it without denormPreserve; NVIDIA does).
    let pdfs = [
        0.0f32,
        f32::MIN_POSITIVE,
        1e-30,
        1e-10,
        0.3,
        1.0,
        7.0,
        1e10,
        1e30,
        3e38,
        f32::INFINITY,
    ];
    let mut input = Vec::new();
    for &nl in &counts {
        for &pl in &pdfs {
            for &nb in &counts {
                for &pb in &pdfs {
                    input.push([nl, pl, nb, pb]);
                }
            }
        }
    }
    let out: Vec<[f32; 4]> = k.run(&[0u32; 4], &input, 0, input.len(), 0, input.len());
    for (q, o) in input.iter().zip(&out) {
        let [nl, pl, nb, pb] = q.map(f64::from);
        let [wl, wb, fl, fb] = o.map(f64::from);
        let what = format!("N_L {nl} p_L {pl} N_B {nb} p_B {pb}: {o:?}");
        assert!(o.iter().all(|x| x.is_finite() && *x >= 0.0), "{what}");
        assert!(wl <= 1.0 && wb <= 1.0, "{what}");
        let (a, b) = (nl * pl, nb * pb);
        // Reference in float64 (products of float32 values cannot overflow it, except inf).
        // Two infinite pdfs compare by their counts (mis_ratio).
        let power = |nx: f64, px: f64, ny: f64, py: f64| -> f64 {
            // n p with 0 * inf = 0 (a technique with no samples or zero pdf).
            let prod = |n: f64, p: f64| if n == 0.0 || p == 0.0 { 0.0 } else { n * p };
            let (x, y) = (prod(nx, px), prod(ny, py));
            // (x, y are >= 0 or +inf, never NaN.)
            if x <= 0.0 {
                0.0
            } else if y <= 0.0 {
                1.0
            } else if x.is_infinite() && y.is_infinite() {
                1.0 / (1.0 + (ny / nx).powi(2))
            } else if x.is_infinite() {
                1.0
            } else if y.is_infinite() {
                0.0
            } else {
                let r = y / x;
                1.0 / (1.0 + r * r)
            }
        };
        let (rl, rb) = (power(nl, pl, nb, pb), power(nb, pb, nl, pl));
        // (3e38 is beyond 2^126, where Vulkan leaves division unspecified: mis_div() in mis.glsl.)
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-5 * y.abs() + 1e-30;
        assert!(
            close(wl, rl) && close(wb, rb),
            "{what}: expected {rl}, {rb}"
        );
        if a > 0.0 && b > 0.0 {
            assert!((wl + wb - 1.0).abs() < 1e-6, "{what}");
        }
        // D-BRDF per-(lobe, light) factors: bounded by 1/(2 N_B) and 1/N_B when N_B > 0.
        if nb > 0.0 {
            assert!(fl <= 0.5 / nb * (1.0 + 1e-6), "{what}");
            assert!(fb <= 1.0 / nb * (1.0 + 1e-6), "{what}");
            if pb > 0.0 {
                assert!(close(fb, rb / nb), "{what}: BRDF factor");
            }
            if pl > 0.0 && pb > 0.0 && nl > 0.0 && a.is_finite() && b.is_finite() {
                // C_L = (1/N_L) p_B / p_L * w_L.
                let expected = pb / pl / nl * rl;
                assert!(
                    (fl - expected).abs() <= 1e-5 * expected + 1e-30,
                    "{what}: light factor {expected}"
                );
            }
        }
    }
    assert_no_validation_messages(&ctx);
}
