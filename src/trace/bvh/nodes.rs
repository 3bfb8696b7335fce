//! The node layout the kernels walk (glsl/trace/bvh.glsl): binary trees collapsed into
//! 4-wide nodes whose children's boxes are quantized to 8 bits per plane on a grid over the
//! node's box (`BvhNode`, 64 bytes, 14 of its 16 words used), so that one small fetch tests four
//! boxes. See src/trace/bvh/mod.rs for the measurements that chose this layout.

use super::builder::{Aabb, BinaryBvh};
use crate::layout::*;

/// Children per node.
pub const WIDTH: usize = 4;

/// The link of a leaf of `count` primitives from `first`.
pub fn leaf_link(first: u32, count: u32) -> u32 {
    debug_assert!((1..=BVH_MAX_LEAF).contains(&count) && first <= BVH_LEAF_FIRST_MASK);
    BVH_LEAF_BIT | ((count - 1) << BVH_LEAF_COUNT_SHIFT) | first
}

pub fn is_leaf(link: u32) -> bool {
    link & BVH_LEAF_BIT != 0
}

/// Quantizes the boxes of a node's children (at most four, with their links) conservatively:
/// every quantized box contains its child's box with a margin that covers the rounding of the
/// kernels' slab test (a few ulp of the node's extent and of the coordinates).
pub fn quantize(children: &[(Aabb, u32)]) -> BvhNode {
    debug_assert!(children.len() <= WIDTH);
    let mut node = BvhNode {
        links: [NONE; 4],
        ..Default::default()
    };
    let mut bounds = Aabb::EMPTY;
    for (b, _) in children {
        bounds = bounds.union(*b);
    }
    let mut exponents = 0u32;
    for axis in 0..3 {
        let (lo, hi) = (f64::from(bounds.lo[axis]), f64::from(bounds.hi[axis]));
        let slack = 1e-6 * (hi - lo) + (lo.abs().max(hi.abs())) * (1.0 / (1u64 << 22) as f64);
        let mut origin = (lo - slack) as f32;
        if f64::from(origin) > lo - slack {
            origin = origin.next_down();
        }
        let origin64 = f64::from(origin);
        let extent = hi + slack - origin64;
        // The smallest power-of-two step whose 255 steps span the extent. Steps stay at or above
        // 2^-100, so that step / d (the kernels' slope) neither underflows nor is a denormal,
        // which lavapipe may flush to zero.
        const MIN_E: i32 = -100;
        let mut e = if extent > 0.0 {
            (extent / 255.0).log2().ceil().clamp(MIN_E as f64, 127.0) as i32
        } else {
            MIN_E
        };
        while e < 127 && 255.0 * 2f64.powi(e) < extent {
            e += 1;
        }
        while e > MIN_E && 255.0 * 2f64.powi(e - 1) >= extent {
            e -= 1;
        }
        let step = 2f64.powi(e);
        node.origin[axis] = origin;
        exponents |= ((e + 127) as u32) << (8 * axis);
        let (mut qlo, mut qhi) = (0u32, 0u32);
        for (k, (b, _)) in children.iter().enumerate() {
            let (clo, chi) = (f64::from(b.lo[axis]), f64::from(b.hi[axis]));
            let l = ((clo - slack - origin64) / step).floor().clamp(0.0, 255.0) as u32;
            let h = ((chi + slack - origin64) / step).ceil().clamp(0.0, 255.0) as u32;
            qlo |= l << (8 * k);
            qhi |= h << (8 * k);
        }
        // Unused slots: an empty box (lo 255 > hi 0), and the NONE link the kernels check.
        for k in children.len()..WIDTH {
            qlo |= 255 << (8 * k);
        }
        match axis {
            0 => (node.lo_x, node.hi_x) = (qlo, qhi),
            1 => (node.lo_y, node.hi_y) = (qlo, qhi),
            _ => (node.lo_z, node.hi_z) = (qlo, qhi),
        }
    }
    node.scale = exponents;
    for (k, (_, link)) in children.iter().enumerate() {
        node.links[k] = *link;
    }
    node
}

/// Collapses `bin` into wide nodes appended to `nodes` (node links are indices into `nodes`;
/// leaf links hold leaf-order positions, unoffset). `leaf_need(first, count)` is the stack depth
/// a leaf adds (top-level leaves: the marker plus the instance's own tree). Returns the root link
/// (a leaf link when the whole tree is one leaf, NONE when it is empty) and the stack depth a
/// walk of it may reach.
pub fn collapse(
    bin: &BinaryBvh,
    nodes: &mut Vec<BvhNode>,
    leaf_need: &dyn Fn(u32, u32) -> u32,
) -> (u32, u32) {
    collapse_as(bin, nodes, leaf_need, Open::LargestArea)
}

/// Which inner child a wide node opens next.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Open {
    /// The largest by surface area (Wald et al. 2008): the fewest node visits.
    LargestArea,
    /// The shallowest, then the largest: every wide node spans two binary levels on every path
    /// that goes on, so a walk of a binary tree of depth D needs at most 3 ceil(D / 2) entries.
    /// (By area, a path can take 3 entries per binary level where children are alike.)
    Shallowest,
}

/// [`collapse`], opening children as `open` says.
pub fn collapse_as(
    bin: &BinaryBvh,
    nodes: &mut Vec<BvhNode>,
    leaf_need: &dyn Fn(u32, u32) -> u32,
    open: Open,
) -> (u32, u32) {
    if bin.nodes.is_empty() {
        return (NONE, 0);
    }
    collapse_node(bin, 0, nodes, leaf_need, open)
}

fn collapse_node(
    bin: &BinaryBvh,
    i: u32,
    nodes: &mut Vec<BvhNode>,
    leaf_need: &dyn Fn(u32, u32) -> u32,
    open: Open,
) -> (u32, u32) {
    let n = &bin.nodes[i as usize];
    if n.count > 0 {
        return (leaf_link(n.a, n.count), leaf_need(n.a, n.count));
    }
    // Open an inner child until the node has WIDTH children: (binary node, levels below n).
    let mut children = vec![(n.a, 1u32), (n.b, 1)];
    while children.len() < WIDTH {
        let inner = children
            .iter()
            .enumerate()
            .filter(|&(_, &(c, _))| bin.nodes[c as usize].count == 0)
            .map(|(k, &(c, level))| (k, level, bin.nodes[c as usize].bounds.half_area()));
        let pick = match open {
            Open::LargestArea => inner.max_by(|a, b| a.2.total_cmp(&b.2)),
            Open::Shallowest => inner.max_by(|a, b| b.1.cmp(&a.1).then(a.2.total_cmp(&b.2))),
        };
        let Some((k, level, _)) = pick else {
            break;
        };
        let c = bin.nodes[children[k].0 as usize];
        children[k] = (c.a, level + 1);
        children.insert(k + 1, (c.b, level + 1));
    }
    let index = nodes.len();
    nodes.push(BvhNode::default());
    let mut quantized = Vec::with_capacity(children.len());
    let mut need = 0;
    for &(c, _) in &children {
        let (link, child_need) = collapse_node(bin, c, nodes, leaf_need, open);
        need = need.max(child_need);
        quantized.push((bin.nodes[c as usize].bounds, link));
    }
    nodes[index] = quantize(&quantized);
    // Visiting the nearest child leaves the others on the stack.
    (index as u32, need + children.len() as u32 - 1)
}

/// Shifts a subtree's links into the global arrays: nodes by `node_offset`, leaf positions by
/// `prim_offset`.
pub fn offset_link(link: u32, node_offset: u32, prim_offset: u32) -> u32 {
    if link == NONE {
        NONE
    } else if is_leaf(link) {
        let first = (link & BVH_LEAF_FIRST_MASK) + prim_offset;
        (link & !BVH_LEAF_FIRST_MASK) | first
    } else {
        link + node_offset
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;

    /// Decodes child `k`'s box exactly (f64) from a quantized node.
    fn decode(n: &BvhNode, k: usize) -> ([f64; 3], [f64; 3]) {
        let planes = [(n.lo_x, n.hi_x), (n.lo_y, n.hi_y), (n.lo_z, n.hi_z)];
        let mut lo = [0.0; 3];
        let mut hi = [0.0; 3];
        for a in 0..3 {
            let step = 2f64.powi(((n.scale >> (8 * a)) & 0xff) as i32 - 127);
            let byte = |w: u32| f64::from((w >> (8 * k)) & 0xff);
            lo[a] = f64::from(n.origin[a]) + byte(planes[a].0) * step;
            hi[a] = f64::from(n.origin[a]) + byte(planes[a].1) * step;
        }
        (lo, hi)
    }

    #[test]
    fn quantized_boxes_contain_their_children() {
        let mut x = 0x1234_5678u32;
        let mut rnd = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x as f32 / u32::MAX as f32
        };
        for case in 0..2000 {
            // Scales from tiny to large, far from the origin or not, flat boxes included.
            let scale = 10f32.powi(case % 9 - 4);
            let offset = Vec3A::new(rnd(), rnd(), rnd()) * 10f32.powi(case % 7 - 1);
            let count = 1 + case as usize % WIDTH;
            let children: Vec<(Aabb, u32)> = (0..count)
                .map(|k| {
                    let lo = offset + Vec3A::new(rnd(), rnd(), rnd()) * scale;
                    let mut ext = Vec3A::new(rnd(), rnd(), rnd()) * scale * 0.3;
                    if case % 5 == 0 {
                        ext.y = 0.0;
                    }
                    (Aabb { lo, hi: lo + ext }, k as u32)
                })
                .collect();
            let n = quantize(&children);
            for (k, (b, link)) in children.iter().enumerate() {
                let (lo, hi) = decode(&n, k);
                for a in 0..3 {
                    assert!(
                        lo[a] <= f64::from(b.lo[a]),
                        "case {case} child {k} axis {a}"
                    );
                    assert!(
                        hi[a] >= f64::from(b.hi[a]),
                        "case {case} child {k} axis {a}"
                    );
                }
                assert_eq!(n.links[k], *link);
            }
            for k in count..WIDTH {
                assert_eq!(n.links[k], NONE);
            }
        }
    }
}
