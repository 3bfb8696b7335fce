//! The light tree (docs/techniques.md, "The light tree"; Conty Estevez & Kulla 2018, pbrt-v4
//! `BVHLightSampler`): a binary tree over the finite lights (rect, disk, sphere, triangle; emissive
//! geometry included), one light per leaf, each node with the bounds, emitted power and orientation
//! cone of its subtree. Light samples descend it from the root choosing a child with probability
//! proportional to its importance at the shading point (glsl/lights/light_tree.glsl); the
//! probability of a given light is recomputed by replaying its root-to-leaf trail, so that MIS
//! weights of BRDF samples use the sampler's own PMF. The infinite lights (dome, sun) are not in
//! the tree: direct lighting loops over them as over few lights.
//!
//! Build: top-down, 12 buckets per axis over the centroids, the split minimising CK18's surface
//! area orientation heuristic (pbrt's `EvaluateCost`); a median split where no bucket split exists,
//! and wherever the depth budget of a 32-bit trail could run out.

use super::dome::luminance;
use super::lights::light_bounds;
use crate::layout::*;
use glam::{DQuat, DVec3, Vec3};
use std::f64::consts::PI;

/// The bounds of a set of emitters as the tree's importance sees them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub lo: DVec3,
    pub hi: DVec3,
    /// Emitted power (luminance, W-like units of the scene).
    pub power: f64,
    /// Unit axis of the cone bounding the emitters' normals.
    pub axis: DVec3,
    /// Half-angle of that cone.
    pub theta_o: f64,
    /// Emission beyond the normals (π/2: Lambertian).
    pub theta_e: f64,
    pub two_sided: bool,
}

/// The tree as uploaded.
pub struct LightTree {
    pub nodes: Vec<GpuLightTreeNode>,
    /// Per light index: the bits of its leaf's path (bit k set: second child at depth k); 0 for
    /// the infinite lights, which are not in the tree.
    pub trails: Vec<u32>,
    /// Deepest leaf (root = 0).
    pub depth: u32,
}

/// Half-angle widening of every stored cone, so that rounding never makes it too narrow.
const CONE_SLACK: f64 = 1e-5;

/// A finite light's bounds; None for the infinite lights. `mean_texel` gives the mean RGB of a
/// texture (emission textures scale the radiance, so textured lights count at their mean).
pub fn light_bounds_of(l: &GpuLight, mean_texel: &dyn Fn(u32) -> Vec3) -> Option<Bounds> {
    let (lo, hi) = light_bounds(l)?;
    let mut radiance = Vec3::from(l.radiance);
    if l.texture != NONE {
        radiance *= mean_texel(l.texture);
    }
    let two_sided = l.flags & LIGHT_FLAG_TWO_SIDED != 0;
    let d3 = |v: &[f32]| DVec3::new(v[0].into(), v[1].into(), v[2].into());
    let (p1, p2) = (d3(&l.p1), d3(&l.p2[..3]));
    // Emitted power of a Lambertian emitter: pi A L per side.
    let sides = if two_sided { 2.0 } else { 1.0 };
    let power = PI * f64::from(l.area) * luminance(radiance.as_dvec3()) * sides;
    let (axis, theta_o) = match l.kind {
        LIGHT_SPHERE => (DVec3::Z, PI),
        LIGHT_DISK => (p1.normalize_or_zero(), 0.0),
        _ => (p1.cross(p2).normalize_or_zero(), 0.0), // rect, triangle: normalize(e1 x e2)
    };
    // A degenerate normal (zero area) bounds nothing: the whole sphere.
    let theta_o = if axis == DVec3::ZERO { PI } else { theta_o };
    Some(Bounds {
        lo: lo.as_dvec3(),
        hi: hi.as_dvec3(),
        power,
        axis: if axis == DVec3::ZERO { DVec3::Z } else { axis },
        theta_o,
        theta_e: PI / 2.0,
        two_sided,
    })
}

/// Mean RGB of a texture's texels (a textured emitter's power counts at its mean).
pub fn texture_mean(t: &crate::scene::Texture) -> Vec3 {
    let sum = t
        .texels
        .iter()
        .fold(DVec3::ZERO, |a, v| a + v.truncate().as_dvec3());
    (sum / t.texels.len().max(1) as f64).as_vec3()
}

/// The cone containing both (CK18 Alg. 1; pbrt `Union(DirectionCone, DirectionCone)`).
fn cone_union(a: (DVec3, f64), b: (DVec3, f64)) -> (DVec3, f64) {
    let theta_d = a.0.angle_between(b.0);
    if (theta_d + b.1).min(PI) <= a.1 {
        return a;
    }
    if (theta_d + a.1).min(PI) <= b.1 {
        return b;
    }
    let theta_o = (a.1 + theta_d + b.1) / 2.0;
    if theta_o >= PI {
        return (a.0, PI);
    }
    let wr = a.0.cross(b.0);
    if wr.length_squared() < 1e-24 {
        return (a.0, PI);
    }
    let w = DQuat::from_axis_angle(wr.normalize(), theta_o - a.1) * a.0;
    (w.normalize(), theta_o)
}

impl Bounds {
    pub fn union(&self, o: &Bounds) -> Bounds {
        let (axis, theta_o) = cone_union((self.axis, self.theta_o), (o.axis, o.theta_o));
        Bounds {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
            power: self.power + o.power,
            axis,
            theta_o,
            theta_e: self.theta_e.max(o.theta_e),
            two_sided: self.two_sided || o.two_sided,
        }
    }

    fn centroid(&self) -> DVec3 {
        0.5 * (self.lo + self.hi)
    }

    /// pbrt-v4 `EvaluateCost` (CK18's SAOH without the parent's constant factors).
    fn cost(&self, kr: f64) -> f64 {
        let (to, te) = (self.theta_o, self.theta_e);
        let tw = (to + te).min(PI);
        let m_omega = 2.0 * PI * (1.0 - to.cos())
            + PI / 2.0
                * (2.0 * tw * to.sin() - (to - 2.0 * tw).cos() - 2.0 * to * to.sin() + to.cos());
        let d = self.hi - self.lo;
        let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
        self.power * m_omega * kr * area
    }
}

/// Builds the tree over `lights` (their indices in the light buffer); None when no light is
/// finite. Fails if there are 2^31 lights or more (the leaf flag's bit).
pub fn build(
    lights: &[GpuLight],
    mean_texel: &dyn Fn(u32) -> Vec3,
) -> crate::error::Result<Option<LightTree>> {
    if lights.len() >= LIGHT_TREE_LEAF as usize {
        return Err(crate::error::Error::Invalid(format!(
            "{} lights: the light tree holds at most {}",
            lights.len(),
            LIGHT_TREE_LEAF - 1
        )));
    }
    let mut items: Vec<(u32, Bounds)> = lights
        .iter()
        .enumerate()
        .filter_map(|(i, l)| light_bounds_of(l, mean_texel).map(|b| (i as u32, b)))
        .collect();
    if items.is_empty() {
        return Ok(None);
    }
    let mut b = Builder {
        nodes: Vec::with_capacity(2 * items.len()),
        trails: vec![0; lights.len()],
        depth: 0,
        root_power: 0.0,
    };
    b.root_power = items.iter().map(|i| i.1.power).sum::<f64>();
    b.split(&mut items, 0, 0);
    Ok(Some(LightTree {
        nodes: b.nodes,
        trails: b.trails,
        depth: b.depth,
    }))
}

struct Builder {
    nodes: Vec<GpuLightTreeNode>,
    trails: Vec<u32>,
    depth: u32,
    root_power: f64,
}

const BUCKETS: usize = 12;

impl Builder {
    fn push(&mut self, b: &Bounds, link: u32) -> usize {
        let f3 = |v: DVec3| v.as_vec3().to_array();
        // Relative power, kept above zero for an emitter that emits (its PMF must not vanish).
        let rel = if self.root_power > 0.0 {
            b.power / self.root_power
        } else {
            0.0
        };
        let power = if rel > 0.0 {
            (rel as f32).max(1e-30)
        } else {
            0.0
        };
        let widen = |t: f64| (t + CONE_SLACK).min(PI).cos() as f32;
        self.nodes.push(GpuLightTreeNode {
            lo: f3(b.lo),
            power,
            hi: f3(b.hi),
            link,
            axis: f3(b.axis),
            cos_o: if b.theta_o >= PI {
                -1.0
            } else {
                widen(b.theta_o)
            },
            cos_e: if b.theta_e >= PI / 2.0 - 1e-12 && b.theta_e <= PI / 2.0 + 1e-12 {
                0.0 // exactly Lambertian
            } else {
                widen(b.theta_e)
            },
            flags: if b.two_sided { LIGHT_TREE_TWO_SIDED } else { 0 },
            ..Default::default()
        });
        self.nodes.len() - 1
    }

    fn split(&mut self, items: &mut [(u32, Bounds)], depth: u32, trail: u32) {
        let bounds = items[1..].iter().fold(items[0].1, |a, i| a.union(&i.1));
        if items.len() == 1 {
            self.push(&bounds, items[0].0 | LIGHT_TREE_LEAF);
            self.trails[items[0].0 as usize] = trail;
            self.depth = self.depth.max(depth);
            return;
        }
        let node = self.push(&bounds, 0);
        let mid = self.partition(items, &bounds, depth);
        let (l, r) = items.split_at_mut(mid);
        self.split(l, depth + 1, trail);
        self.nodes[node].link = self.nodes.len() as u32;
        self.split(r, depth + 1, trail | 1 << depth);
    }

    /// Reorders `items` and returns the size of the first child's part (in 1..len).
    fn partition(&self, items: &mut [(u32, Bounds)], bounds: &Bounds, depth: u32) -> usize {
        let n = items.len();
        let (clo, chi) = items.iter().fold(
            (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
            |(a, b), i| (a.min(i.1.centroid()), b.max(i.1.centroid())),
        );
        let ext = chi - clo;
        let widest = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let median = |items: &mut [(u32, Bounds)]| {
            let mid = n / 2;
            items.select_nth_unstable_by(mid, |a, b| {
                a.1.centroid()[widest].total_cmp(&b.1.centroid()[widest])
            });
            mid
        };
        // Depth budget: a median split below here keeps every leaf within the trail's bits.
        let need = usize::BITS - (n - 1).leading_zeros();
        if depth + need >= LIGHT_TREE_MAX_DEPTH - 1 {
            return median(items);
        }
        let diag = bounds.hi - bounds.lo;
        let mut best = (f64::INFINITY, 0usize, 0usize);
        for axis in 0..3 {
            if ext[axis].is_nan() || ext[axis] <= 0.0 {
                continue;
            }
            let bucket = |b: &Bounds| {
                let t = (b.centroid()[axis] - clo[axis]) / ext[axis];
                ((t * BUCKETS as f64) as usize).min(BUCKETS - 1)
            };
            let mut acc: [Option<Bounds>; BUCKETS] = [None; BUCKETS];
            for i in items.iter() {
                let k = bucket(&i.1);
                acc[k] = Some(acc[k].map_or(i.1, |a| a.union(&i.1)));
            }
            let kr = diag.max_element() / diag[axis].max(1e-300);
            let merge = |r: &[Option<Bounds>]| {
                r.iter()
                    .flatten()
                    .fold(None::<Bounds>, |a, b| Some(a.map_or(*b, |a| a.union(b))))
            };
            for s in 0..BUCKETS - 1 {
                let (Some(l), Some(r)) = (merge(&acc[..=s]), merge(&acc[s + 1..])) else {
                    continue;
                };
                let cost = l.cost(kr) + r.cost(kr);
                if cost < best.0 {
                    best = (cost, axis, s);
                }
            }
        }
        if !best.0.is_finite() {
            return median(items);
        }
        let (axis, s) = (best.1, best.2);
        let bucket = |b: &Bounds| {
            let t = (b.centroid()[axis] - clo[axis]) / ext[axis];
            ((t * BUCKETS as f64) as usize).min(BUCKETS - 1)
        };
        let mut mid = 0;
        for i in 0..n {
            if bucket(&items[i].1) <= s {
                items.swap(i, mid);
                mid += 1;
            }
        }
        if mid == 0 || mid == n {
            median(items)
        } else {
            mid
        }
    }
}

/// The tree's importance of `node` at point `p` with normal `n`, in f64 (the float64 twin of
/// `light_tree_importance` in glsl/lights/light_tree.glsl, for tests and diagnostics).
pub fn importance(node: &GpuLightTreeNode, p: DVec3, n: DVec3) -> f64 {
    let d3 = |v: [f32; 3]| DVec3::new(v[0].into(), v[1].into(), v[2].into());
    let (lo, hi) = (d3(node.lo), d3(node.hi));
    let c = 0.5 * (lo + hi);
    let r2 = (0.5 * (hi - lo)).length_squared();
    let power = f64::from(node.power);
    let pc = p - c;
    let d2 = pc.length_squared();
    if d2 <= r2 {
        return power / r2.max(1e-30);
    }
    let d = d2.sqrt();
    let wi = pc / d;
    let sin_u = (r2 / d2).sqrt();
    let cos_u = (1.0 - sin_u * sin_u).max(0.0).sqrt();
    let mut cos_w = d3(node.axis).dot(wi);
    if node.flags & LIGHT_TREE_TWO_SIDED != 0 {
        cos_w = cos_w.abs();
    }
    let cos_o = f64::from(node.cos_o);
    let sin = |c: f64| (1.0 - c * c).max(0.0).sqrt();
    let (sin_w, sin_o) = (sin(cos_w), sin(cos_o));
    let (cos_x, sin_x) = if cos_w > cos_o {
        (1.0, 0.0)
    } else {
        (cos_w * cos_o + sin_w * sin_o, sin_w * cos_o - cos_w * sin_o)
    };
    let cos_p = if cos_x > cos_u {
        1.0
    } else {
        cos_x * cos_u + sin_x * sin_u
    };
    if cos_p <= f64::from(node.cos_e) {
        return 0.0;
    }
    let cos_i = -n.dot(wi);
    let cos_ip = if cos_i > cos_u {
        1.0
    } else {
        cos_i * cos_u + sin(cos_i) * sin_u
    };
    if cos_ip <= 0.0 {
        return 0.0;
    }
    power * cos_p * cos_ip / d2
}

impl LightTree {
    /// The probability that a light sample at (p, n) picks light `light`, in f64, by replaying
    /// its trail (0 for a light outside the tree or on a path of zero importance).
    pub fn pmf(&self, p: DVec3, n: DVec3, light: u32) -> f64 {
        let mut trail = self.trails[light as usize];
        let (mut i, mut pmf) = (0usize, 1.0);
        loop {
            let node = &self.nodes[i];
            if node.link & LIGHT_TREE_LEAF != 0 {
                return if node.link & !LIGHT_TREE_LEAF == light {
                    pmf
                } else {
                    0.0
                };
            }
            let second = node.link as usize;
            let c0 = importance(&self.nodes[i + 1], p, n);
            let c1 = importance(&self.nodes[second], p, n);
            if (c0 + c1).is_nan() || c0 + c1 <= 0.0 {
                return 0.0;
            }
            let right = trail & 1 != 0;
            trail >>= 1;
            pmf *= if right { c1 } else { c0 } / (c0 + c1);
            i = if right { second } else { i + 1 };
        }
    }

    /// The probability that a descent at (p, n) ends at a node whose children both have zero
    /// importance (no light: the sample is 0).
    pub fn pmf_none(&self, p: DVec3, n: DVec3) -> f64 {
        let mut stack = vec![(0usize, 1.0f64)];
        let mut none = 0.0;
        while let Some((i, q)) = stack.pop() {
            let node = &self.nodes[i];
            if node.link & LIGHT_TREE_LEAF != 0 {
                continue;
            }
            let second = node.link as usize;
            let c0 = importance(&self.nodes[i + 1], p, n);
            let c1 = importance(&self.nodes[second], p, n);
            if (c0 + c1).is_nan() || c0 + c1 <= 0.0 {
                none += q;
                continue;
            }
            if c0 > 0.0 {
                stack.push((i + 1, q * c0 / (c0 + c1)));
            }
            if c1 > 0.0 {
                stack.push((second, q * c1 / (c0 + c1)));
            }
        }
        none
    }
}

#[cfg(test)]
#[path = "light_tree_tests.rs"]
mod tests;
