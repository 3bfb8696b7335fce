//! The light BVH: a binary tree over the bounds of the finite lights (rect, disk, sphere,
//! triangle), so that a BRDF sample finds the lights it crosses in O(log n) instead of testing
//! every light (docs/techniques.md, "The light BVH for BRDF samples"). Infinite lights (dome, sun)
//! are listed after the tree's references and always tested. Median split on the longest axis of
//! the centroids; leaves of at most two lights.

use crate::layout::*;
use glam::Vec3;

pub struct LightBvh {
    pub nodes: Vec<GpuLightNode>,
    /// Light indices in leaf order, then the infinite lights.
    pub refs: Vec<u32>,
    pub infinite_first: u32,
    pub infinite_count: u32,
}

/// Bounds of a finite light, padded so that rounding never misses a crossing; None for the
/// infinite lights.
pub fn light_bounds(l: &GpuLight) -> Option<(Vec3, Vec3)> {
    let p0 = Vec3::from_slice(&l.p0[..3]);
    let p1 = Vec3::from_slice(&l.p1[..3]);
    let p2 = Vec3::from_slice(&l.p2[..3]);
    let (lo, hi) = match l.kind {
        LIGHT_SPHERE => (p0 - Vec3::splat(l.p0[3]), p0 + Vec3::splat(l.p0[3])),
        LIGHT_RECT => {
            let e = (p1.abs() + p2.abs()) * 0.5;
            (p0 - e, p0 + e)
        }
        LIGHT_DISK => {
            let e = (Vec3::ONE - p1 * p1).max(Vec3::ZERO).powf(0.5) * l.p0[3];
            (p0 - e, p0 + e)
        }
        LIGHT_TRIANGLE => {
            let (a, b, c) = (p0, p0 + p1, p0 + p2);
            (a.min(b).min(c), a.max(b).max(c))
        }
        _ => return None,
    };
    let pad = (hi - lo) * 1e-4 + (lo.abs().max(hi.abs())) * 1e-6 + Vec3::splat(1e-7);
    Some((lo - pad, hi + pad))
}

pub fn build(lights: &[GpuLight]) -> LightBvh {
    let mut finite: Vec<(u32, Vec3, Vec3)> = Vec::new();
    let mut infinite = Vec::new();
    for (i, l) in lights.iter().enumerate() {
        match light_bounds(l) {
            Some((lo, hi)) => finite.push((i as u32, lo, hi)),
            None => infinite.push(i as u32),
        }
    }
    let mut nodes = vec![GpuLightNode::default()];
    let mut refs = Vec::with_capacity(lights.len());
    if finite.is_empty() {
        nodes.clear();
    } else {
        let n = finite.len();
        split(&mut finite[..], 0, &mut nodes, &mut refs);
        debug_assert_eq!(refs.len(), n);
    }
    let infinite_first = refs.len() as u32;
    let infinite_count = infinite.len() as u32;
    refs.extend(infinite);
    LightBvh {
        nodes,
        refs,
        infinite_first,
        infinite_count,
    }
}

fn split(
    items: &mut [(u32, Vec3, Vec3)],
    node: usize,
    nodes: &mut Vec<GpuLightNode>,
    refs: &mut Vec<u32>,
) {
    let lo = items.iter().fold(Vec3::splat(f32::MAX), |a, i| a.min(i.1));
    let hi = items.iter().fold(Vec3::splat(f32::MIN), |a, i| a.max(i.2));
    nodes[node].lo = lo.to_array();
    nodes[node].hi = hi.to_array();
    if items.len() <= 2 {
        nodes[node].index = refs.len() as u32;
        nodes[node].count = items.len() as u32;
        refs.extend(items.iter().map(|i| i.0));
        return;
    }
    let c = |i: &(u32, Vec3, Vec3)| (i.1 + i.2) * 0.5;
    let (clo, chi) = items.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(a, b), i| (a.min(c(i)), b.max(c(i))),
    );
    let ext = chi - clo;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |a, b| c(a)[axis].total_cmp(&c(b)[axis]));
    let left = nodes.len();
    nodes.push(GpuLightNode::default());
    nodes.push(GpuLightNode::default());
    nodes[node].index = left as u32;
    nodes[node].count = 0;
    let (l, r) = items.split_at_mut(mid);
    split(l, left, nodes, refs);
    split(r, left + 1, nodes, refs);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_light_is_referenced_once_and_inside_its_leaf() {
        let mut lights = Vec::new();
        for i in 0..37 {
            let f = i as f32;
            lights.push(GpuLight {
                kind: [LIGHT_SPHERE, LIGHT_RECT, LIGHT_DISK, LIGHT_TRIANGLE][i % 4],
                p0: [f.sin() * 10.0, f.cos() * 3.0, f * 0.5, 0.2],
                p1: [0.0, 1.0, 0.0],
                p2: [0.3, 0.0, 0.1, 0.0],
                ..Default::default()
            });
        }
        lights.push(GpuLight {
            kind: LIGHT_DOME,
            ..Default::default()
        });
        lights.push(GpuLight {
            kind: LIGHT_SUN,
            ..Default::default()
        });
        let bvh = build(&lights);
        let mut seen = bvh.refs.clone();
        seen.sort();
        assert_eq!(seen, (0..39).collect::<Vec<u32>>());
        assert_eq!((bvh.infinite_first, bvh.infinite_count), (37, 2));
        for n in &bvh.nodes {
            if n.count > 0 {
                for &r in &bvh.refs[n.index as usize..(n.index + n.count) as usize] {
                    let (lo, hi) = light_bounds(&lights[r as usize]).unwrap();
                    assert!(lo.cmpge(Vec3::from(n.lo)).all() && hi.cmple(Vec3::from(n.hi)).all());
                }
            }
        }
    }
}
