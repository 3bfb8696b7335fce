//! Binned surface-area-heuristic builder of binary BVHs over boxes: a mesh's triangles, or the top
//! level's instances and shapes. Top-down; each split is chosen among `BINS` planes per axis
//! (Wald 2007, "On fast construction of SAH-based bounding volume hierarchies"). Large subtrees are
//! built on their own threads (std::thread::scope), and the binning pass of very large nodes is
//! split over the threads too, so that the first levels are not serial.

use glam::{Vec3A, Vec4};

/// An axis-aligned box; empty when `lo > hi`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub lo: Vec3A,
    pub hi: Vec3A,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        lo: Vec3A::splat(f32::INFINITY),
        hi: Vec3A::splat(f32::NEG_INFINITY),
    };

    pub fn from_points(points: &[Vec3A]) -> Aabb {
        let mut b = Aabb::EMPTY;
        for &p in points {
            b.grow(p);
        }
        b
    }

    pub fn grow(&mut self, p: Vec3A) {
        self.lo = self.lo.min(p);
        self.hi = self.hi.max(p);
    }

    #[must_use]
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.lo.cmpgt(self.hi).any()
    }

    /// Half the surface area (the SAH only needs ratios); 0 for an empty box.
    pub fn half_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let d = self.hi - self.lo;
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    pub fn centre(&self) -> Vec3A {
        (self.lo + self.hi) * 0.5
    }
}

/// A node of the binary tree. Inner nodes have `count == 0` and children `a`, `b`; leaves hold
/// `count` primitives from position `a` of [`BinaryBvh::order`].
#[derive(Clone, Copy, Debug)]
pub struct BinaryNode {
    pub bounds: Aabb,
    pub a: u32,
    pub b: u32,
    pub count: u32,
}

/// A binary BVH: `nodes[0]` is the root; leaves index `order`, the primitives in leaf order.
pub struct BinaryBvh {
    pub nodes: Vec<BinaryNode>,
    pub order: Vec<u32>,
}

#[derive(Clone, Copy, Debug)]
pub struct BuildParams {
    /// Most primitives in a leaf.
    pub max_leaf: usize,
    /// Cost of traversing a node relative to intersecting one primitive.
    pub traversal_cost: f32,
    /// Depth from which splits are object medians, so that the depth stays bounded.
    pub median_depth: u32,
    /// Most levels of the binary tree: a node whose primitives would not fit below it in
    /// balanced (object-median) splits takes one, so that no input, however degenerate (a
    /// million identical triangles), builds a deeper tree. At least the depth of a balanced
    /// tree, [`balanced_depth`].
    pub max_depth: u32,
    /// Threads the build may use.
    pub threads: usize,
}

impl Default for BuildParams {
    fn default() -> Self {
        BuildParams {
            max_leaf: 8,
            traversal_cost: 1.0,
            median_depth: 40,
            max_depth: u32::MAX,
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
        }
    }
}

const BINS: usize = 16;
/// Nodes with at most this many primitives try every split between sorted centroids.
const SWEEP: usize = 6;
/// Nodes with at least this many primitives hand one child to another thread.
const PARALLEL_SUBTREE: usize = 8192;
/// Nodes with at least this many primitives bin on every thread they have.
const PARALLEL_BINNING: usize = 1 << 17;

/// A primitive's box with its index in `lo.w`, moved (not indexed) as the build partitions, so
/// that every pass streams through memory. The index is stored as the bits of a normal float
/// (exponent bit 30 set): denormals in the unused lane would slow every SIMD operation down.
#[derive(Clone, Copy)]
struct PrimRef {
    lo: Vec4,
    hi: Vec4,
}

impl PrimRef {
    fn bounds(&self) -> Aabb {
        Aabb {
            lo: Vec3A::from_vec4(self.lo),
            hi: Vec3A::from_vec4(self.hi),
        }
    }
    /// Twice the centroid (the build only compares centroids).
    fn centroid2(&self) -> Vec3A {
        Vec3A::from_vec4(self.lo) + Vec3A::from_vec4(self.hi)
    }
    fn id(&self) -> u32 {
        self.lo.w.to_bits() & !ID_TAG
    }
}

const ID_TAG: u32 = 0x4000_0000;
/// Most primitives one build takes (their indices must fit below `ID_TAG`'s exponent range).
pub const MAX_PRIMITIVES: usize = 1 << 27;

type Bins = [[Aabb; BINS]; 3];
type Counts = [[u32; BINS]; 3];

/// Builds a binary BVH over `boxes` (none may be empty).
pub fn build(boxes: &[Aabb], params: &BuildParams) -> BinaryBvh {
    let params = BuildParams {
        max_leaf: params.max_leaf.max(1),
        threads: params.threads.max(1),
        ..*params
    };
    assert!(
        boxes.len() <= MAX_PRIMITIVES,
        "too many primitives for one BVH"
    );
    let mut refs: Vec<PrimRef> = boxes
        .iter()
        .enumerate()
        .map(|(i, b)| PrimRef {
            lo: b.lo.extend(f32::from_bits(ID_TAG | i as u32)),
            hi: b.hi.extend(0.0),
        })
        .collect();
    let mut nodes = Vec::with_capacity(2 * boxes.len() / params.max_leaf.max(2) + 1);
    if !refs.is_empty() {
        let (bounds, cb) = bounds_of(&refs);
        build_rec(
            &params,
            &mut refs,
            0,
            bounds,
            cb,
            0,
            params.threads,
            &mut nodes,
        );
    }
    BinaryBvh {
        nodes,
        order: refs.iter().map(PrimRef::id).collect(),
    }
}

fn bin_prims(refs: &[PrimRef], cb: &Aabb, scale: Vec3A, bins: &mut Bins, counts: &mut Counts) {
    for r in refs {
        let b = r.bounds();
        let k = ((r.centroid2() - cb.lo) * scale)
            .min(Vec3A::splat((BINS - 1) as f32))
            .max(Vec3A::ZERO);
        for axis in 0..3 {
            let i = k[axis] as usize;
            bins[axis][i] = bins[axis][i].union(b);
            counts[axis][i] += 1;
        }
    }
}

fn bin_parallel(
    refs: &[PrimRef],
    cb: &Aabb,
    scale: Vec3A,
    threads: usize,
    bins: &mut Bins,
    counts: &mut Counts,
) {
    if threads < 2 || refs.len() < PARALLEL_BINNING {
        return bin_prims(refs, cb, scale, bins, counts);
    }
    let chunk = refs.len().div_ceil(threads);
    let parts: Vec<(Bins, Counts)> = std::thread::scope(|s| {
        let handles: Vec<_> = refs
            .chunks(chunk)
            .map(|c| {
                s.spawn(move || {
                    let mut b = [[Aabb::EMPTY; BINS]; 3];
                    let mut n = [[0; BINS]; 3];
                    bin_prims(c, cb, scale, &mut b, &mut n);
                    (b, n)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("BVH binning thread panicked"))
            .collect()
    });
    for (pb, pn) in parts {
        for axis in 0..3 {
            for k in 0..BINS {
                bins[axis][k] = bins[axis][k].union(pb[axis][k]);
                counts[axis][k] += pn[axis][k];
            }
        }
    }
}

/// The cheapest split: axis, first bin of the right side, SAH cost (areas times counts), and
/// both sides' boxes.
struct Split {
    axis: usize,
    bin: usize,
    cost: f32,
    left: Aabb,
    right: Aabb,
}

fn best_split(bins: &Bins, counts: &Counts, cb: &Aabb) -> Option<Split> {
    let mut best: Option<Split> = None;
    for axis in 0..3 {
        if cb.hi[axis] <= cb.lo[axis] {
            continue;
        }
        let (row, count) = (&bins[axis], &counts[axis]);
        // Right-to-left sweep: the box and count of the right side of every split.
        let mut right = [Aabb::EMPTY; BINS];
        let mut right_n = [0u32; BINS];
        let mut acc = Aabb::EMPTY;
        let mut n = 0;
        for k in (1..BINS).rev() {
            if count[k] != 0 {
                acc = acc.union(row[k]);
                n += count[k];
            }
            right[k] = acc;
            right_n[k] = n;
        }
        let mut left = Aabb::EMPTY;
        let mut ln = 0;
        for k in 1..BINS {
            // An empty bin moves no primitive across: the same split as the previous plane.
            if count[k - 1] == 0 {
                continue;
            }
            left = left.union(row[k - 1]);
            ln += count[k - 1];
            if right_n[k] == 0 {
                break;
            }
            let cost = left.half_area() * ln as f32 + right[k].half_area() * right_n[k] as f32;
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(Split {
                    axis,
                    bin: k,
                    cost,
                    left,
                    right: right[k],
                });
            }
        }
    }
    best
}

/// The box and the (doubled) centroid box of `refs`.
fn bounds_of(refs: &[PrimRef]) -> (Aabb, Aabb) {
    let mut b = Aabb::EMPTY;
    let mut c = Aabb::EMPTY;
    for r in refs {
        b = b.union(r.bounds());
        c.grow(r.centroid2());
    }
    (b, c)
}

fn centroid_bounds(refs: &[PrimRef]) -> Aabb {
    let mut c = Aabb::EMPTY;
    for r in refs {
        c.grow(r.centroid2());
    }
    c
}

/// Splits at the object median along the widest centroid axis (or, with all centroids equal, in
/// the middle of the list). Returns the left count.
fn median_split(refs: &mut [PrimRef], cb: &Aabb) -> usize {
    let mid = refs.len() / 2;
    let ext = cb.hi - cb.lo;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    if ext[axis] > 0.0 {
        refs.select_nth_unstable_by(mid, |a, b| {
            a.centroid2()[axis].total_cmp(&b.centroid2()[axis])
        });
    }
    mid
}

/// Levels of inner nodes a tree of object-median splits needs over `n` primitives with leaves
/// of at most `max_leaf`: the least d with ceil(n / 2^d) <= max_leaf (median splits halve, the
/// larger half rounding up).
pub fn balanced_depth(n: usize, max_leaf: usize) -> u32 {
    let mut d = 0;
    let mut m = n;
    while m > max_leaf.max(1) {
        m = m.div_ceil(2);
        d += 1;
    }
    d
}

/// An object-median split with both sides' boxes.
fn median(refs: &mut [PrimRef], cb: &Aabb) -> (usize, (Aabb, Aabb), (Aabb, Aabb)) {
    let nl = median_split(refs, cb);
    let (l, r) = refs.split_at(nl);
    (nl, bounds_of(l), bounds_of(r))
}

/// The cheapest split of a few primitives sorted by centroid along each axis: (axis, left
/// count, SAH cost as areas times counts).
fn sweep_split(refs: &[PrimRef]) -> Option<(usize, usize, f32)> {
    let n = refs.len();
    let mut best: Option<(usize, usize, f32)> = None;
    let mut order = [0u8; SWEEP];
    let mut right = [0.0f32; SWEEP];
    for axis in 0..3 {
        let key = |i: u8| refs[i as usize].centroid2()[axis];
        for (i, o) in order[..n].iter_mut().enumerate() {
            *o = i as u8;
        }
        order[..n].sort_unstable_by(|&a, &b| key(a).total_cmp(&key(b)));
        if key(order[0]) == key(order[n - 1]) {
            continue;
        }
        let mut acc = Aabb::EMPTY;
        for k in (1..n).rev() {
            acc = acc.union(refs[order[k] as usize].bounds());
            right[k] = acc.half_area() * (n - k) as f32;
        }
        let mut left = Aabb::EMPTY;
        for k in 1..n {
            left = left.union(refs[order[k - 1] as usize].bounds());
            // Only between distinct centroids, so that sorting the primitives reproduces it.
            if key(order[k - 1]) == key(order[k]) {
                continue;
            }
            let cost = left.half_area() * k as f32 + right[k];
            if best.is_none_or(|b| cost < b.2) {
                best = Some((axis, k, cost));
            }
        }
    }
    best
}

#[allow(clippy::too_many_arguments)]
fn build_rec(
    p: &BuildParams,
    refs: &mut [PrimRef],
    first: u32,
    bounds: Aabb,
    cb: Aabb,
    depth: u32,
    threads: usize,
    out: &mut Vec<BinaryNode>,
) -> u32 {
    let n = refs.len();
    let index = out.len() as u32;
    let leaf = BinaryNode {
        bounds,
        a: first,
        b: 0,
        count: n as u32,
    };
    // Object medians from here if the depth budget only leaves room for a balanced subtree.
    let medians = depth >= p.median_depth
        || depth.saturating_add(balanced_depth(n, p.max_leaf)) >= p.max_depth;
    if n == 1 || (n <= p.max_leaf && medians) {
        out.push(leaf);
        return index;
    }
    let area = bounds.half_area().max(f32::MIN_POSITIVE);
    let (nl, left, right) = if medians {
        median(refs, &cb)
    } else if n <= SWEEP {
        // Few primitives: every split between sorted centroids, cheaper than binning.
        match sweep_split(refs) {
            Some((axis, k, cost)) => {
                if n <= p.max_leaf && n as f32 <= p.traversal_cost + cost / area {
                    out.push(leaf);
                    return index;
                }
                refs.sort_unstable_by(|a, b| a.centroid2()[axis].total_cmp(&b.centroid2()[axis]));
                let (l, r) = refs.split_at(k);
                (k, bounds_of(l), bounds_of(r))
            }
            None if n <= p.max_leaf => {
                out.push(leaf);
                return index;
            }
            None => median(refs, &cb),
        }
    } else {
        let ext = cb.hi - cb.lo;
        let scale = Vec3A::select(
            ext.cmpgt(Vec3A::ZERO),
            Vec3A::splat(BINS as f32) / ext,
            Vec3A::ZERO,
        );
        let mut bins = [[Aabb::EMPTY; BINS]; 3];
        let mut counts = [[0; BINS]; 3];
        bin_parallel(refs, &cb, scale, threads, &mut bins, &mut counts);
        match best_split(&bins, &counts, &cb) {
            Some(s) => {
                // SAH in units of one primitive intersection over this node's area.
                if n <= p.max_leaf && n as f32 <= p.traversal_cost + s.cost / area {
                    out.push(leaf);
                    return index;
                }
                let (axis, bin, lo, sc) = (s.axis, s.bin, cb.lo[s.axis], scale[s.axis]);
                let nl = partition(refs, |r| {
                    (((r.centroid2()[axis] - lo) * sc) as usize).min(BINS - 1) < bin
                });
                let (l, r) = refs.split_at(nl);
                (
                    nl,
                    (s.left, centroid_bounds(l)),
                    (s.right, centroid_bounds(r)),
                )
            }
            None if n <= p.max_leaf => {
                out.push(leaf);
                return index;
            }
            None => median(refs, &cb),
        }
    };
    out.push(BinaryNode {
        bounds,
        a: 0,
        b: 0,
        count: 0,
    });
    let (lp, rp) = refs.split_at_mut(nl);
    let rfirst = first + nl as u32;
    let (a, b) = if threads >= 2 && lp.len().min(rp.len()) >= PARALLEL_SUBTREE {
        let lt = threads / 2;
        let rt = threads - lt;
        let (a, right_nodes) = std::thread::scope(|s| {
            let h = s.spawn(move || {
                let mut v = Vec::with_capacity(2 * rp.len() / p.max_leaf.max(2) + 1);
                build_rec(p, rp, rfirst, right.0, right.1, depth + 1, rt, &mut v);
                v
            });
            let a = build_rec(p, lp, first, left.0, left.1, depth + 1, lt, out);
            (a, h.join().expect("BVH build thread panicked"))
        });
        let offset = out.len() as u32;
        out.extend(right_nodes.into_iter().map(|mut node| {
            if node.count == 0 {
                node.a += offset;
                node.b += offset;
            }
            node
        }));
        (a, offset)
    } else {
        let a = build_rec(p, lp, first, left.0, left.1, depth + 1, threads, out);
        let b = build_rec(p, rp, rfirst, right.0, right.1, depth + 1, threads, out);
        (a, b)
    };
    out[index as usize].a = a;
    out[index as usize].b = b;
    index
}

/// Moves the elements for which `left` holds to the front; returns their count.
fn partition<T>(v: &mut [T], left: impl Fn(&T) -> bool) -> usize {
    let mut i = 0;
    let mut j = v.len();
    while i < j {
        if left(&v[i]) {
            i += 1;
        } else {
            j -= 1;
            v.swap(i, j);
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(bvh: &BinaryBvh, boxes: &[Aabb], max_leaf: usize) {
        let mut seen = vec![false; boxes.len()];
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            let n = bvh.nodes[i as usize];
            if n.count == 0 {
                for c in [n.a, n.b] {
                    let cb = bvh.nodes[c as usize].bounds;
                    assert!(n.bounds.lo.cmple(cb.lo).all() && n.bounds.hi.cmpge(cb.hi).all());
                    stack.push(c);
                }
            } else {
                assert!(n.count as usize <= max_leaf);
                for &p in &bvh.order[n.a as usize..(n.a + n.count) as usize] {
                    let b = boxes[p as usize];
                    assert!(n.bounds.lo.cmple(b.lo).all() && n.bounds.hi.cmpge(b.hi).all());
                    assert!(!seen[p as usize]);
                    seen[p as usize] = true;
                }
            }
        }
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn every_primitive_once_and_boxes_nest() {
        let mut boxes = Vec::new();
        let mut x = 12345u32;
        let mut rnd = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x as f32) / (u32::MAX as f32)
        };
        for _ in 0..50_000 {
            let p = Vec3A::new(rnd(), rnd(), rnd()) * 100.0;
            boxes.push(Aabb {
                lo: p,
                hi: p + Vec3A::new(rnd(), rnd(), rnd()),
            });
        }
        // Identical boxes: no split plane separates them.
        boxes.extend(std::iter::repeat_n(boxes[0], 100));
        for threads in [1, 4] {
            let params = BuildParams {
                threads,
                ..Default::default()
            };
            let bvh = build(&boxes, &params);
            check(&bvh, &boxes, params.max_leaf);
        }
    }
}
