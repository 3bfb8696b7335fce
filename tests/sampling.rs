//! glsl/lights/light_sampling.glsl, irradiance.glsl and mis.glsl on the GPU (tests/kernels/
//! sample_light.comp, irradiance_check.comp, mis_check.comp), and the dome tables of
//! src/gpu_scene/dome.rs: chi-square tests of every light sampler against its own pdf(), pdf
//! consistency per sample, analytic irradiance against float64 references validated by Monte Carlo
//! (z-tests), the MIS weights at extreme pdfs, and the camera-sample streams (scrambled Sobol).

#[path = "sampling/camera_streams.rs"]
mod camera_streams;
#[path = "sampling/dome.rs"]
mod dome_sampling;
mod sampling_support;

use glam::DVec3;
use illum::layout::*;
use illum::stress::closed_form::{polygon_irradiance, sphere_irradiance};
use sampling_support::*;
use std::f64::consts::PI;

const N: usize = 1 << 20;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct LightParams {
    dome: GpuDomeSampling,
    light: GpuLight,
    p: [f32; 4],
}

fn f4(v: DVec3, w: f64) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w as f32]
}
fn d3<const N: usize>(v: [f32; N]) -> DVec3 {
    DVec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]))
}

fn light(kind: u32, p0: [f32; 4], p1: [f32; 4], p2: [f32; 4], two_sided: bool) -> GpuLight {
    GpuLight {
        p0,
        p1: [p1[0], p1[1], p1[2]],
        triangle: 0,
        p2,
        radiance: [1.0; 3],
        kind,
        texture: NONE,
        shape: NONE,
        flags: if two_sided { LIGHT_FLAG_TWO_SIDED } else { 0 },
        area: 0.0,
        ..Default::default()
    }
}

fn rect(c: DVec3, u: DVec3, v: DVec3, two_sided: bool) -> GpuLight {
    light(LIGHT_RECT, f4(c, 0.0), f4(u, 0.0), f4(v, 0.0), two_sided)
}
fn sphere(c: DVec3, r: f64, two_sided: bool) -> GpuLight {
    light(LIGHT_SPHERE, f4(c, r), [0.0; 4], [0.0; 4], two_sided)
}
fn disk(c: DVec3, n: DVec3, r: f64, two_sided: bool) -> GpuLight {
    let n = n.normalize();
    let (t, _) = basis(n);
    light(LIGHT_DISK, f4(c, r), f4(n, 0.0), f4(t, 0.0), two_sided)
}
fn triangle(v0: DVec3, e1: DVec3, e2: DVec3, two_sided: bool) -> GpuLight {
    light(
        LIGHT_TRIANGLE,
        f4(v0, 0.0),
        f4(e1, 0.0),
        f4(e2, 0.0),
        two_sided,
    )
}
/// Sun toward `dir` with angular radius `half_deg` (as the uploader stores it).
fn sun(dir: DVec3, half_deg: f64) -> GpuLight {
    let h = half_deg.to_radians();
    let om = 2.0 * (0.5 * h).sin().powi(2);
    light(
        LIGHT_SUN,
        f4(dir.normalize(), h.cos()),
        [om as f32, 0.0, 0.0, 0.0],
        [0.0; 4],
        false,
    )
}
fn dome_light(rotation_deg: f64) -> GpuLight {
    let r = rotation_deg.to_radians();
    light(
        LIGHT_DOME,
        [r.cos() as f32, r.sin() as f32, 0.0, 0.0],
        [0.0; 4],
        [0.0; 4],
        false,
    )
}

/// Mode-0 output of sample_light.comp: (wi, pdf), (x, pdf(wi)), (uv, dist, hit t), (n, delta).
struct Samples(Vec<[f32; 4]>);

impl Samples {
    fn wi(&self, i: usize) -> DVec3 {
        d3(self.0[4 * i])
    }
    fn pdf(&self, i: usize) -> f64 {
        f64::from(self.0[4 * i][3])
    }
    fn x(&self, i: usize) -> DVec3 {
        d3(self.0[4 * i + 1])
    }
    fn pdf_eval(&self, i: usize) -> f64 {
        f64::from(self.0[4 * i + 1][3])
    }
    fn uv(&self, i: usize) -> (f64, f64) {
        let o = self.0[4 * i + 2];
        (o[0].into(), o[1].into())
    }
    fn dist(&self, i: usize) -> f64 {
        f64::from(self.0[4 * i + 2][2])
    }
    fn hit_t(&self, i: usize) -> f64 {
        f64::from(self.0[4 * i + 2][3])
    }
    fn delta(&self, i: usize) -> bool {
        self.0[4 * i + 3][3] != 0.0
    }
}

struct Lights {
    ctx: illum::vk::Context,
    k: Kernel,
}

impl Lights {
    fn new() -> Lights {
        let ctx = context();
        let k = Kernel::new(&ctx, "sample_light", illum_test_kernels::SAMPLE_LIGHT_PLAIN);
        Lights { ctx, k }
    }
    fn sample(&self, prm: &LightParams, n: usize, seed: u32) -> Samples {
        Samples(self.k.run(prm, &[[0f32; 4]], 0, n, seed, 4 * n))
    }
    /// light_hit() for each direction: (pdf, t, uv).
    fn hit(&self, prm: &LightParams, dirs: &[[f32; 4]]) -> Vec<[f32; 4]> {
        self.k.run(prm, dirs, 1, dirs.len(), 0, dirs.len())
    }
    fn finish(self) {
        assert_no_validation_messages(&self.ctx);
    }

    /// Draws N samples, checks them one by one, and runs the chi-square test on `domain`.
    /// `ambiguous(uv)` marks samples on a boundary where the pdf may legitimately jump.
    fn check(
        &self,
        name: &str,
        prm: &LightParams,
        domain: &Domain,
        seed: u32,
        ambiguous: &dyn Fn((f64, f64)) -> bool,
    ) {
        let out = self.sample(prm, N, seed);
        let p = d3(prm.p);
        let area_light = prm.light.kind != LIGHT_SUN && prm.light.kind != LIGHT_DOME;
        let mut valid = Vec::with_capacity(N);
        let mut pdfs = Vec::with_capacity(N);
        for i in 0..N {
            let pdf = out.pdf(i);
            assert!(
                pdf >= 0.0 && pdf.is_finite(),
                "{name}: sample {i} has pdf {pdf}"
            );
            if pdf == 0.0 {
                // No sample (a hemisphere direction that misses a nearly enclosing emitter): the
                // normalisation test below counts it against the pdf's integral.
                continue;
            }
            assert!(!out.delta(i));
            let wi = out.wi(i);
            assert!(
                (wi.length() - 1.0).abs() < 1e-5,
                "{name}: |wi| = {}",
                wi.length()
            );
            valid.push(wi);
            pdfs.push((pdf, out.pdf_eval(i)));
            let (u, v) = out.uv(i);
            assert!(
                (0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v),
                "{name}: uv ({u}, {v})"
            );
            if area_light {
                // x = p + dist wi, and light_hit() finds the same point.
                let (x, d) = (out.x(i), out.dist(i));
                assert!(
                    (x - p - d * wi).length() <= 1e-5 * (d + p.length()),
                    "{name}: sample {i}: x is not at dist {d} along wi"
                );
                // Both are float32; near a sphere's silhouette t = d cos - sqrt(r^2 - d^2 sin^2) is
                // ill-conditioned: the square root's argument carries ~2 ulp(r^2 + d^2).
                let mut tol = 1e-4 * d;
                if prm.light.kind == LIGHT_SPHERE {
                    let (c, r) = (d3(prm.light.p0), f64::from(prm.light.p0[3]));
                    let dc = c - p;
                    let sin2 = wi.normalize().cross(dc.normalize()).length_squared();
                    let q = (r * r - dc.length_squared() * sin2).max(1e-14);
                    tol += 4e-7 * (r * r + dc.length_squared()) / q.sqrt();
                }
                assert!(
                    (out.hit_t(i) - d).abs() <= tol,
                    "{name}: sample {i}: dist {d} but light_hit() t = {}",
                    out.hit_t(i)
                );
            } else {
                assert_eq!(out.dist(i), f64::INFINITY);
            }
        }
        let mismatches = check_reported_pdfs(name, &pdfs, |i| ambiguous(out.uv(i)));
        if mismatches > 0 {
            eprintln!("{name}: {mismatches} samples on texel boundaries with a neighbour's pdf");
        }
        sampler_test(name, &valid, N, domain, &mut |dirs| {
            self.hit(prm, dirs)
                .iter()
                .map(|o| f64::from(o[0]))
                .collect()
        });
    }
}

fn params(light: GpuLight, p: DVec3) -> LightParams {
    LightParams {
        dome: GpuDomeSampling::default(),
        light,
        p: f4(p, 0.0),
    }
}

fn never(_: (f64, f64)) -> bool {
    false
}

// ---------------------------------------------------------------------------------------------
// Domains on the lights' surfaces (all geometry read back from the float32 light, as the GPU sees it)

fn rect_domain(l: &GpuLight, p: DVec3) -> Domain {
    let (c, eu, ev) = (d3(l.p0), d3(l.p1), d3(l.p2));
    let s = c - 0.5 * eu - 0.5 * ev;
    let nn = eu.cross(ev);
    let (area, n) = (nn.length(), nn.normalize());
    Domain::surface(
        p,
        move |x, y| (s + x * eu + y * ev, n, area),
        move |p, d| {
            let t = (c - p).dot(n) / d.dot(n);
            let q = p + t * d - s;
            let (x, y) = (
                q.dot(eu) / eu.length_squared(),
                q.dot(ev) / ev.length_squared(),
            );
            let tol = 1e-4;
            (t > 0.0 && x > -tol && x < 1.0 + tol && y > -tol && y < 1.0 + tol)
                .then_some((x.clamp(0.0, 1.0), y.clamp(0.0, 1.0)))
        },
        32,
        32,
    )
}

fn disk_domain(l: &GpuLight, p: DVec3) -> Domain {
    let (c, r, n, t) = (d3(l.p0), f64::from(l.p0[3]), d3(l.p1), d3(l.p2));
    let b = n.cross(t);
    Domain::surface(
        p,
        move |x, y| {
            let (rr, phi) = (r * x.sqrt(), 2.0 * PI * y);
            (c + rr * (phi.cos() * t + phi.sin() * b), n, PI * r * r)
        },
        move |p, d| {
            let tt = (c - p).dot(n) / d.dot(n);
            let q = p + tt * d - c;
            let x = q.length_squared() / (r * r);
            let y = q.dot(b).atan2(q.dot(t)).rem_euclid(2.0 * PI) / (2.0 * PI);
            (tt > 0.0 && x < 1.0 + 1e-4).then_some((x.min(1.0), y))
        },
        24,
        48,
    )
}

fn triangle_domain(l: &GpuLight, p: DVec3) -> Domain {
    let (v0, e1, e2) = (d3(l.p0), d3(l.p1), d3(l.p2));
    let nn = e1.cross(e2);
    let (area, n) = (0.5 * nn.length(), nn.normalize());
    Domain::surface(
        p,
        move |x, y| {
            let s = x.sqrt();
            (v0 + s * (1.0 - y) * e1 + s * y * e2, n, area)
        },
        move |p, d| {
            let t = (v0 - p).dot(n) / d.dot(n);
            let q = p + t * d - v0;
            // Solve q = b1 e1 + b2 e2 (normal equations).
            let (a11, a12, a22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
            let (r1, r2) = (q.dot(e1), q.dot(e2));
            let det = a11 * a22 - a12 * a12;
            let b1 = (r1 * a22 - r2 * a12) / det;
            let b2 = (r2 * a11 - r1 * a12) / det;
            let tol = 1e-4;
            if !(t > 0.0 && b1 > -tol && b2 > -tol && b1 + b2 < 1.0 + tol) {
                return None;
            }
            let (b1, b2) = (b1.max(0.0), b2.max(0.0));
            let s = b1 + b2;
            Some(((s * s).min(1.0), if s > 0.0 { b2 / s } else { 0.0 }))
        },
        32,
        32,
    )
}

/// The inner side of a sphere seen from p inside it, parametrised by (1 - z)/2 and azimuth.
fn sphere_inside_domain(l: &GpuLight, p: DVec3) -> Domain {
    let (c, r) = (d3(l.p0), f64::from(l.p0[3]));
    Domain::surface(
        p,
        move |x, y| {
            let z = 1.0 - 2.0 * x;
            let s = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * PI * y;
            let n = DVec3::new(s * phi.cos(), s * phi.sin(), z);
            (c + r * n, n, 4.0 * PI * r * r)
        },
        move |p, d| {
            let f = p - c;
            let b = -f.dot(d);
            let l = f + b * d;
            let t = b + (r * r - l.length_squared()).max(0.0).sqrt();
            let n = (p + t * d - c) / r;
            let y = n.y.atan2(n.x).rem_euclid(2.0 * PI) / (2.0 * PI);
            Some((((1.0 - n.z) / 2.0).clamp(0.0, 1.0), y))
        },
        32,
        32,
    )
}

/// Cone about `axis` with 1 - cos(theta_cap) = om. Float32 directions resolve angles to ~1e-7 rad, so
/// samples up to 1% beyond the cap (in 1 - cos) are counted in the outer ring (relevant only for the
/// 1e-4 rad cones).
fn cone_domain(axis: DVec3, om: f64, nx: usize, ny: usize) -> Domain {
    let mut d = Domain::cone(axis, om, nx, ny);
    let (t, b) = basis(axis);
    d.from_dir = Box::new(move |dir| {
        let h = 0.5 * angle(dir, axis);
        let omc = 2.0 * h.sin() * h.sin();
        let phi = dir.dot(b).atan2(dir.dot(t)).rem_euclid(2.0 * PI);
        (omc <= 1.01 * om).then_some(((omc / om).min(1.0), phi / (2.0 * PI)))
    });
    d
}

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
    let mut rng = HostRng(77);
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

/// Whether the ray from p along d meets the emitting side of light l (None within 1e-4 of an edge).
fn meets(l: &GpuLight, p: DVec3, d: DVec3) -> Option<bool> {
    let two = l.flags & LIGHT_FLAG_TWO_SIDED != 0;
    let plane = |c: DVec3, n: DVec3| -> Option<(DVec3, f64)> {
        let front = (p - c).dot(n) > 0.0;
        if !front && !two {
            return None;
        }
        let t = (c - p).dot(n) / d.dot(n);
        (t > 0.0).then_some((p + t * d - c, t))
    };
    match l.kind {
        LIGHT_RECT => {
            let (c, eu, ev) = (d3(l.p0), d3(l.p1), d3(l.p2));
            let Some((q, _)) = plane(c, eu.cross(ev)) else {
                return Some(false);
            };
            let (x, y) = (
                q.dot(eu) / eu.length_squared(),
                q.dot(ev) / ev.length_squared(),
            );
            let m = x.abs().max(y.abs());
            ((m - 0.5).abs() > 1e-4).then_some(m < 0.5)
        }
        LIGHT_DISK => {
            let (c, r, n) = (d3(l.p0), f64::from(l.p0[3]), d3(l.p1));
            let Some((q, _)) = plane(c, n) else {
                return Some(false);
            };
            let x = q.length() / r;
            ((x - 1.0).abs() > 1e-4).then_some(x < 1.0)
        }
        LIGHT_TRIANGLE => {
            let (v0, e1, e2) = (d3(l.p0), d3(l.p1), d3(l.p2));
            let Some((q, _)) = plane(v0, e1.cross(e2)) else {
                return Some(false);
            };
            let (a11, a12, a22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
            let (r1, r2) = (q.dot(e1), q.dot(e2));
            let det = a11 * a22 - a12 * a12;
            let b1 = (r1 * a22 - r2 * a12) / det;
            let b2 = (r2 * a11 - r1 * a12) / det;
            let m = b1.min(b2).min(1.0 - b1 - b2);
            (m.abs() > 1e-4).then_some(m > 0.0)
        }
        LIGHT_SPHERE => {
            let (c, r) = (d3(l.p0), f64::from(l.p0[3]));
            let dc = c - p;
            if dc.length() <= r {
                return Some(two);
            }
            let s = (r / dc.length()).asin();
            let a = angle(d, dc.normalize());
            ((a - s).abs() > 1e-4).then_some(a < s)
        }
        LIGHT_SUN => {
            let a = angle(d, d3(l.p0));
            let s = f64::from(l.p0[3]).acos();
            ((a - s).abs() > 1e-4).then_some(a < s)
        }
        _ => None,
    }
}

/// splitmix64, for host-side Monte Carlo.
struct HostRng(u64);

impl HostRng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
    fn sphere(&mut self) -> DVec3 {
        let z = 1.0 - 2.0 * self.next();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * self.next();
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

// ---------------------------------------------------------------------------------------------
// Irradiance

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
fn irradiance_mc(
    l: &GpuLight,
    p: DVec3,
    n: DVec3,
    samples: usize,
    rng: &mut HostRng,
) -> (f64, f64) {
    let (t, b) = basis(n);
    let mut hits = 0usize;
    let mut ambiguous = 0usize;
    for _ in 0..samples {
        let (u1, u2) = (rng.next(), rng.next());
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
    let mut rng = HostRng(2024);
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
