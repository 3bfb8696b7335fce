//! GPU lights built from host geometry for the light test kernels (tests/kernels/sample_light.comp,
//! irradiance_check.comp), the sample_light.comp harness that checks a sampler sample by sample
//! and by a chi-square test, the domains of those tests on the lights' surfaces, and the host's
//! float64 ray-light test.

use super::{Domain, Kernel, angle, assert_no_validation_messages, basis, check_reported_pdfs};
use super::{context, d3, f4, sampler_test};
use glam::DVec3;
use illum::layout::*;
use std::f64::consts::PI;

/// Samples of each chi-square case.
const SAMPLES: usize = 1 << 20;

/// The parameters of sample_light.comp: a light (with its dome tables) and the shading point.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LightParams {
    pub dome: GpuDomeSampling,
    pub light: GpuLight,
    pub p: [f32; 4],
}

pub fn light(kind: u32, p0: [f32; 4], p1: [f32; 4], p2: [f32; 4], two_sided: bool) -> GpuLight {
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

pub fn rect(c: DVec3, u: DVec3, v: DVec3, two_sided: bool) -> GpuLight {
    light(LIGHT_RECT, f4(c, 0.0), f4(u, 0.0), f4(v, 0.0), two_sided)
}
pub fn sphere(c: DVec3, r: f64, two_sided: bool) -> GpuLight {
    light(LIGHT_SPHERE, f4(c, r), [0.0; 4], [0.0; 4], two_sided)
}
pub fn disk(c: DVec3, n: DVec3, r: f64, two_sided: bool) -> GpuLight {
    let n = n.normalize();
    let (t, _) = basis(n);
    light(LIGHT_DISK, f4(c, r), f4(n, 0.0), f4(t, 0.0), two_sided)
}
pub fn triangle(v0: DVec3, e1: DVec3, e2: DVec3, two_sided: bool) -> GpuLight {
    light(
        LIGHT_TRIANGLE,
        f4(v0, 0.0),
        f4(e1, 0.0),
        f4(e2, 0.0),
        two_sided,
    )
}
/// Sun toward `dir` with angular radius `half_deg` (as the uploader stores it).
pub fn sun(dir: DVec3, half_deg: f64) -> GpuLight {
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
pub fn dome_light(rotation_deg: f64) -> GpuLight {
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
pub struct Samples(Vec<[f32; 4]>);

impl Samples {
    pub fn wi(&self, i: usize) -> DVec3 {
        d3(self.0[4 * i])
    }
    pub fn pdf(&self, i: usize) -> f64 {
        f64::from(self.0[4 * i][3])
    }
    pub fn x(&self, i: usize) -> DVec3 {
        d3(self.0[4 * i + 1])
    }
    pub fn pdf_eval(&self, i: usize) -> f64 {
        f64::from(self.0[4 * i + 1][3])
    }
    pub fn uv(&self, i: usize) -> (f64, f64) {
        let o = self.0[4 * i + 2];
        (o[0].into(), o[1].into())
    }
    pub fn dist(&self, i: usize) -> f64 {
        f64::from(self.0[4 * i + 2][2])
    }
    pub fn hit_t(&self, i: usize) -> f64 {
        f64::from(self.0[4 * i + 2][3])
    }
    pub fn delta(&self, i: usize) -> bool {
        self.0[4 * i + 3][3] != 0.0
    }
}

/// sample_light.comp on a validated context.
pub struct Lights {
    pub ctx: illum::vk::Context,
    k: Kernel,
}

impl Lights {
    pub fn new() -> Lights {
        let ctx = context();
        let k = Kernel::new(&ctx, "sample_light", illum_test_kernels::SAMPLE_LIGHT_PLAIN);
        Lights { ctx, k }
    }
    pub fn sample(&self, prm: &LightParams, n: usize, seed: u32) -> Samples {
        Samples(self.k.run(prm, &[[0f32; 4]], 0, n, seed, 4 * n))
    }
    /// light_hit() for each direction: (pdf, t, uv).
    pub fn hit(&self, prm: &LightParams, dirs: &[[f32; 4]]) -> Vec<[f32; 4]> {
        self.k.run(prm, dirs, 1, dirs.len(), 0, dirs.len())
    }
    /// Ends the test: validation must have stayed silent.
    pub fn finish(self) {
        assert_no_validation_messages(&self.ctx);
    }

    /// Draws [`SAMPLES`] samples, checks them one by one, and runs the chi-square test on `domain`.
    /// `ambiguous(uv)` marks samples on a boundary where the pdf may legitimately jump.
    pub fn check(
        &self,
        name: &str,
        prm: &LightParams,
        domain: &Domain,
        seed: u32,
        ambiguous: &dyn Fn((f64, f64)) -> bool,
    ) {
        let out = self.sample(prm, SAMPLES, seed);
        let p = d3(prm.p);
        let area_light = prm.light.kind != LIGHT_SUN && prm.light.kind != LIGHT_DOME;
        let mut valid = Vec::with_capacity(SAMPLES);
        let mut pdfs = Vec::with_capacity(SAMPLES);
        for i in 0..SAMPLES {
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
        sampler_test(name, &valid, SAMPLES, domain, &mut |dirs| {
            self.hit(prm, dirs)
                .iter()
                .map(|o| f64::from(o[0]))
                .collect()
        });
    }
}

/// `light` seen from `p`, without dome tables.
pub fn params(light: GpuLight, p: DVec3) -> LightParams {
    LightParams {
        dome: GpuDomeSampling::default(),
        light,
        p: f4(p, 0.0),
    }
}

/// No sample is on a boundary where the pdf jumps.
pub fn never(_: (f64, f64)) -> bool {
    false
}

// ---------------------------------------------------------------------------------------------
// Domains on the lights' surfaces (all geometry read back from the float32 light, as the GPU sees it)

pub fn rect_domain(l: &GpuLight, p: DVec3) -> Domain {
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

pub fn disk_domain(l: &GpuLight, p: DVec3) -> Domain {
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

pub fn triangle_domain(l: &GpuLight, p: DVec3) -> Domain {
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
pub fn sphere_inside_domain(l: &GpuLight, p: DVec3) -> Domain {
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
pub fn cone_domain(axis: DVec3, om: f64, nx: usize, ny: usize) -> Domain {
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

/// Whether the ray from p along d meets the emitting side of light l (None within 1e-4 of an edge).
pub fn meets(l: &GpuLight, p: DVec3, d: DVec3) -> Option<bool> {
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
