//! A brute-force f64 reference of the trace interface's semantics, used to judge the rays on
//! which the two trace paths disagree (and, on devices without ray queries, every BVH answer).
//! Hits close to a triangle edge, a shape's rim, the ends of the t range, or at grazing incidence
//! are "marginal": either answer is right for them.

use illum::gpu_scene::GpuScene;
use illum::layout::*;
use illum::trace::query::{HitRecord, Ray};

#[derive(Clone, Copy, Debug)]
pub struct RefHit {
    pub t: f64,
    pub kind: u32,
    pub instance: u32,
    pub prim: u32,
    pub marginal: bool,
    /// How much the hit's t moves for a small move of the surface along its normal, relative to
    /// a head-on hit (1 / |cos| of the incidence angle).
    pub grazing: f64,
}

type V = [f64; 3];
fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: V, b: V) -> V {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn mul(a: V, s: f64) -> V {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V, b: V) -> V {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn len(a: V) -> f64 {
    dot(a, a).sqrt()
}
fn v3(a: &[f32]) -> V {
    [f64::from(a[0]), f64::from(a[1]), f64::from(a[2])]
}

/// Relative width of the band around an edge, rim or t bound in which answers may differ.
const MARGIN: f64 = 2e-5;

/// Every hit of `ray` (within its t range and mask) in `scene`.
pub fn hits(scene: &GpuScene, ray: &Ray) -> Vec<RefHit> {
    let o = v3(&ray.origin);
    let d = v3(&ray.dir);
    let (tmin, tmax) = (f64::from(ray.tmin), f64::from(ray.tmax));
    let scale = len(o) + 1.0;
    let mut out = Vec::new();
    let mut push = |t: f64, kind, instance, prim, marginal: bool, grazing: f64| {
        let band = MARGIN * (t.abs() + scale) / len(d);
        if t > tmin - band && (t < tmax + band) {
            let near_bound =
                (t - tmin).abs() < band || (tmax.is_finite() && (t - tmax).abs() < band);
            if t > tmin && t < tmax || near_bound {
                out.push(RefHit {
                    t,
                    kind,
                    instance,
                    prim,
                    marginal: marginal || near_bound,
                    grazing,
                });
            }
        }
    };
    if ray.mask & MASK_GEOMETRY != 0 {
        for (i, (mesh, rows)) in scene.instances.iter().enumerate() {
            let m = scene.meshes[*mesh as usize];
            let xf = |p: glam::Vec3| -> V {
                let p = [f64::from(p.x), f64::from(p.y), f64::from(p.z)];
                [0, 1, 2].map(|r| dot(v3(&rows[r][..3]), p) + f64::from(rows[r][3]))
            };
            for tri in 0..m.triangle_count {
                let base = (m.first_index + 3 * tri) as usize;
                let p = |k: usize| {
                    xf(scene.positions[(m.first_vertex + scene.indices[base + k]) as usize])
                };
                let (a, b, c) = (p(0), p(1), p(2));
                let (e1, e2) = (sub(b, a), sub(c, a));
                let pv = cross(d, e2);
                let det = dot(e1, pv);
                let grazing = det.abs() <= 1e-6 * len(e1) * len(e2) * len(d);
                if det == 0.0 {
                    continue;
                }
                let s = sub(o, a);
                let u = dot(s, pv) / det;
                let q = cross(s, e1);
                let v = dot(d, q) / det;
                let t = dot(e2, q) / det;
                let w = 1.0 - u - v;
                // Distance to the nearest edge, relative to the triangle's size.
                let edge = MARGIN * (1.0 + scale / len(e1).min(len(e2)).max(1e-30));
                if u < -edge || v < -edge || w < -edge {
                    continue;
                }
                let marginal = grazing || u < edge || v < edge || w < edge;
                let cos = det.abs() / (len(cross(e1, e2)) * len(d));
                push(
                    t,
                    HIT_TRIANGLE,
                    i as u32,
                    tri,
                    marginal,
                    1.0 / cos.max(1e-4),
                );
            }
        }
    }
    for (i, s) in scene.shapes.iter().enumerate() {
        let mask = scene.shape_masks[i];
        if ray.mask & mask == 0 {
            continue;
        }
        let c = v3(&s.p0);
        for (t, marginal, grazing) in shape_hits(s, c, o, d) {
            push(t, HIT_SHAPE, NONE, i as u32, marginal, grazing);
        }
    }
    out
}

/// (t, marginal, grazing) of every hit of a shape.
fn shape_hits(s: &GpuShape, c: V, o: V, d: V) -> Vec<(f64, bool, f64)> {
    let dd = dot(d, d);
    match s.kind {
        SHAPE_SPHERE => {
            let r = f64::from(s.p0[3]);
            let f = sub(o, c);
            let b = dot(f, d);
            let disc = b * b - dd * (dot(f, f) - r * r);
            if disc < -MARGIN * r * r * dd {
                return Vec::new();
            }
            let marginal = disc.abs() <= MARGIN * r * r * dd;
            let sq = disc.max(0.0).sqrt();
            // cos of the incidence angle: sqrt(disc) / (|d| r).
            let grazing = 1.0 / (sq / (dd.sqrt() * r)).max(1e-4);
            vec![
                ((-b - sq) / dd, marginal, grazing),
                ((-b + sq) / dd, marginal, grazing),
            ]
        }
        SHAPE_RECT => {
            let (u, v) = (v3(&s.p1), v3(&s.p2));
            let n = cross(u, v);
            let dn = dot(d, n);
            if dn == 0.0 {
                return Vec::new();
            }
            let t = dot(sub(c, o), n) / dn;
            let q = sub(add(o, mul(d, t)), c);
            let a = [dot(q, u) / dot(u, u), dot(q, v) / dot(v, v)];
            let m = a[0].abs().max(a[1].abs());
            let grazing = dn.abs() <= 1e-6 * len(n) * len(d);
            if m > 0.5 + MARGIN {
                return Vec::new();
            }
            let cos = dn.abs() / (len(n) * len(d));
            vec![(t, grazing || m > 0.5 - MARGIN, 1.0 / cos.max(1e-4))]
        }
        _ => {
            let n = v3(&s.p1);
            let r = f64::from(s.p0[3]);
            let dn = dot(d, n);
            if dn == 0.0 {
                return Vec::new();
            }
            let t = dot(sub(c, o), n) / dn;
            let q = sub(add(o, mul(d, t)), c);
            let rho = len(q) / r;
            let grazing = dn.abs() <= 1e-6 * len(d);
            if rho > 1.0 + MARGIN {
                return Vec::new();
            }
            let cos = dn.abs() / len(d);
            vec![(t, grazing || rho > 1.0 - MARGIN, 1.0 / cos.max(1e-4))]
        }
    }
}

/// Tolerance on t: 1e-5 relative to the distance from the origin of render space (the ray's
/// origin is rounded to f32 there and again in each instance's object space).
pub fn t_tolerance(ray: &Ray, t: f64) -> f64 {
    1e-5 * (t.abs() + len(v3(&ray.origin)) / len(v3(&ray.dir)))
}

/// Why `rec` is not a right answer for `ray`, or None when it is.
pub fn judge(scene: &GpuScene, ray: &Ray, rec: &HitRecord) -> Option<String> {
    let hs = hits(scene, ray);
    let t = f64::from(rec.t);
    let tol = |t: f64| t_tolerance(ray, t);
    let first_solid = hs
        .iter()
        .filter(|h| !h.marginal)
        .min_by(|a, b| a.t.total_cmp(&b.t));
    let closest = if rec.kind == HIT_NONE {
        first_solid.map(|h| format!("missed the solid hit {h:?}"))
    } else if !hs.iter().any(|h| {
        h.kind == rec.kind
            && (rec.kind == HIT_SHAPE || h.instance == rec.instance)
            && h.prim == rec.prim
            && (h.t - t).abs() <= tol(h.t) * h.grazing
    }) {
        Some(format!(
            "reported a hit the reference does not have (reference: {hs:?})"
        ))
    } else {
        first_solid
            .filter(|h| h.t < t - tol(t) * h.grazing)
            .map(|h| format!("a nearer solid hit exists: {h:?}"))
    };
    let occluded = match (rec.occluded != 0, hs.is_empty(), first_solid.is_some()) {
        (true, true, _) => Some("occluded, but nothing is in the way".to_string()),
        (false, _, true) => Some("not occluded, but a solid hit is in the way".to_string()),
        _ => None,
    };
    closest.or(occluded)
}
