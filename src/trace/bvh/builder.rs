//! Binned surface-area-heuristic builder of binary BVHs over boxes: a mesh's triangles, or the top
//! level's instances and shapes. Top-down; each split is chosen among `BINS` planes per axis
//! (Wald 2007, "On fast construction of SAH-based bounding volume hierarchies"). Large subtrees are
//! built on their own threads (std::thread::scope), and the binning pass of very large nodes is
//! split over the threads too, so that the first levels are not serial.

use glam::Vec3A;

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
    /// Threads the build may use.
    pub threads: usize,
}

impl Default for BuildParams {
    fn default() -> Self {
        BuildParams {
            max_leaf: 8,
            traversal_cost: 1.0,
            median_depth: 40,
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
        }
    }
}

const BINS: usize = 16;
/// Nodes with at least this many primitives hand one child to another thread.
const PARALLEL_SUBTREE: usize = 8192;
/// Nodes with at least this many primitives bin on every thread they have.
const PARALLEL_BINNING: usize = 1 << 17;

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    centroids: Aabb,
    count: u32,
}

const EMPTY_BIN: Bin = Bin {
    bounds: Aabb::EMPTY,
    centroids: Aabb::EMPTY,
    count: 0,
};

type Bins = [[Bin; BINS]; 3];

struct Input<'a> {
    boxes: &'a [Aabb],
    centroids: Vec<Vec3A>,
    params: BuildParams,
}

/// Builds a binary BVH over `boxes` (none may be empty).
pub fn build(boxes: &[Aabb], params: &BuildParams) -> BinaryBvh {
    let params = BuildParams {
        max_leaf: params.max_leaf.max(1),
        threads: params.threads.max(1),
        ..*params
    };
    let centroids: Vec<Vec3A> = boxes.iter().map(Aabb::centre).collect();
    let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
    let mut nodes = Vec::with_capacity(2 * boxes.len() / params.max_leaf.max(2) + 1);
    if boxes.is_empty() {
        return BinaryBvh { nodes, order };
    }
    let inp = Input {
        boxes,
        centroids,
        params,
    };
    let mut bounds = Aabb::EMPTY;
    let mut cbounds = Aabb::EMPTY;
    for (b, &c) in boxes.iter().zip(&inp.centroids) {
        bounds = bounds.union(*b);
        cbounds.grow(c);
    }
    build_rec(
        &inp,
        &mut order,
        0,
        bounds,
        cbounds,
        0,
        params.threads,
        &mut nodes,
    );
    BinaryBvh { nodes, order }
}

fn bin_prims(inp: &Input, prims: &[u32], cb: &Aabb, scale: Vec3A) -> Box<Bins> {
    let mut bins = Box::new([[EMPTY_BIN; BINS]; 3]);
    for &p in prims {
        let c = inp.centroids[p as usize];
        let b = inp.boxes[p as usize];
        let k = ((c - cb.lo) * scale)
            .min(Vec3A::splat((BINS - 1) as f32))
            .max(Vec3A::ZERO);
        for (axis, row) in bins.iter_mut().enumerate() {
            let bin = &mut row[k[axis] as usize];
            bin.bounds = bin.bounds.union(b);
            bin.centroids.grow(c);
            bin.count += 1;
        }
    }
    bins
}

fn bin_parallel(inp: &Input, prims: &[u32], cb: &Aabb, scale: Vec3A, threads: usize) -> Box<Bins> {
    if threads < 2 || prims.len() < PARALLEL_BINNING {
        return bin_prims(inp, prims, cb, scale);
    }
    let chunk = prims.len().div_ceil(threads);
    let parts: Vec<Box<Bins>> = std::thread::scope(|s| {
        let handles: Vec<_> = prims
            .chunks(chunk)
            .map(|c| s.spawn(move || bin_prims(inp, c, cb, scale)))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("BVH binning thread panicked"))
            .collect()
    });
    let mut bins = Box::new([[EMPTY_BIN; BINS]; 3]);
    for part in parts {
        for (row, prow) in bins.iter_mut().zip(part.iter()) {
            for (bin, pbin) in row.iter_mut().zip(prow) {
                bin.bounds = bin.bounds.union(pbin.bounds);
                bin.centroids = bin.centroids.union(pbin.centroids);
                bin.count += pbin.count;
            }
        }
    }
    bins
}

/// The chosen split: axis, first bin of the right side, and both sides' boxes.
struct Split {
    axis: usize,
    bin: usize,
    cost: f32,
    left: (Aabb, Aabb),
    right: (Aabb, Aabb),
}

fn best_split(bins: &Bins, cb: &Aabb) -> Option<Split> {
    let mut best: Option<Split> = None;
    for (axis, row) in bins.iter().enumerate() {
        if cb.hi[axis] <= cb.lo[axis] {
            continue;
        }
        // Right-to-left sweep: cost of the right side for every split position.
        let mut right_cost = [0.0f32; BINS];
        let mut acc = Aabb::EMPTY;
        let mut n = 0u32;
        for k in (1..BINS).rev() {
            acc = acc.union(row[k].bounds);
            n += row[k].count;
            right_cost[k] = acc.half_area() * n as f32;
        }
        let mut lb = Aabb::EMPTY;
        let mut lc = Aabb::EMPTY;
        let mut ln = 0u32;
        for k in 1..BINS {
            lb = lb.union(row[k - 1].bounds);
            lc = lc.union(row[k - 1].centroids);
            ln += row[k - 1].count;
            let rn: u32 = row[k..].iter().map(|b| b.count).sum();
            if ln == 0 || rn == 0 {
                continue;
            }
            let cost = lb.half_area() * ln as f32 + right_cost[k];
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                let (rb, rc) = row[k..].iter().fold((Aabb::EMPTY, Aabb::EMPTY), |(b, c), bin| {
                    (b.union(bin.bounds), c.union(bin.centroids))
                });
                best = Some(Split {
                    axis,
                    bin: k,
                    cost,
                    left: (lb, lc),
                    right: (rb, rc),
                });
            }
        }
    }
    best
}

fn bounds_of(inp: &Input, prims: &[u32]) -> (Aabb, Aabb) {
    let mut b = Aabb::EMPTY;
    let mut c = Aabb::EMPTY;
    for &p in prims {
        b = b.union(inp.boxes[p as usize]);
        c.grow(inp.centroids[p as usize]);
    }
    (b, c)
}

/// Splits at the object median along the widest centroid axis (or, with all centroids equal, in
/// the middle of the list). Returns the left count and both sides' boxes.
fn median_split(inp: &Input, prims: &mut [u32], cb: &Aabb) -> (usize, (Aabb, Aabb), (Aabb, Aabb)) {
    let mid = prims.len() / 2;
    let ext = cb.hi - cb.lo;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    if ext[axis] > 0.0 {
        let c = &inp.centroids;
        prims.select_nth_unstable_by(mid, |&a, &b| {
            c[a as usize][axis].total_cmp(&c[b as usize][axis])
        });
    }
    let (l, r) = prims.split_at(mid);
    (mid, bounds_of(inp, l), bounds_of(inp, r))
}

#[allow(clippy::too_many_arguments)]
fn build_rec(
    inp: &Input,
    prims: &mut [u32],
    first: u32,
    bounds: Aabb,
    cb: Aabb,
    depth: u32,
    threads: usize,
    out: &mut Vec<BinaryNode>,
) -> u32 {
    let n = prims.len();
    let index = out.len() as u32;
    let p = &inp.params;
    let leaf = BinaryNode {
        bounds,
        a: first,
        b: 0,
        count: n as u32,
    };
    if n == 1 {
        out.push(leaf);
        return index;
    }
    let (nl, left, right) = if depth >= p.median_depth {
        if n <= p.max_leaf {
            out.push(leaf);
            return index;
        }
        median_split(inp, prims, &cb)
    } else {
        let ext = cb.hi - cb.lo;
        let scale = Vec3A::select(
            ext.cmpgt(Vec3A::ZERO),
            Vec3A::splat(BINS as f32) / ext,
            Vec3A::ZERO,
        );
        let bins = bin_parallel(inp, prims, &cb, scale, threads);
        match best_split(&bins, &cb) {
            Some(s) => {
                // SAH in units of one primitive intersection over this node's area.
                let area = bounds.half_area().max(f32::MIN_POSITIVE);
                let split_cost = p.traversal_cost + s.cost / area;
                if n <= p.max_leaf && n as f32 <= split_cost {
                    out.push(leaf);
                    return index;
                }
                let (axis, bin) = (s.axis, s.bin);
                let lo = cb.lo[axis];
                let sc = scale[axis];
                let c = &inp.centroids;
                let in_left = |q: u32| {
                    let k = (((c[q as usize][axis] - lo) * sc) as usize).min(BINS - 1);
                    k < bin
                };
                let nl = partition(prims, in_left);
                (nl, s.left, s.right)
            }
            None if n <= p.max_leaf => {
                out.push(leaf);
                return index;
            }
            None => median_split(inp, prims, &cb),
        }
    };
    out.push(BinaryNode {
        bounds,
        a: 0,
        b: 0,
        count: 0,
    });
    let (lp, rp) = prims.split_at_mut(nl);
    let rfirst = first + nl as u32;
    let (a, b) = if threads >= 2 && lp.len().min(rp.len()) >= PARALLEL_SUBTREE {
        let lt = threads / 2;
        let rt = threads - lt;
        let (a, right_nodes) = std::thread::scope(|s| {
            let h = s.spawn(move || {
                let mut v = Vec::with_capacity(2 * rp.len() / p.max_leaf.max(2) + 1);
                build_rec(inp, rp, rfirst, right.0, right.1, depth + 1, rt, &mut v);
                v
            });
            let a = build_rec(inp, lp, first, left.0, left.1, depth + 1, lt, out);
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
        let a = build_rec(inp, lp, first, left.0, left.1, depth + 1, threads, out);
        let b = build_rec(inp, rp, rfirst, right.0, right.1, depth + 1, threads, out);
        (a, b)
    };
    out[index as usize].a = a;
    out[index as usize].b = b;
    index
}

/// Moves the elements for which `left` holds to the front; returns their count.
fn partition(v: &mut [u32], left: impl Fn(u32) -> bool) -> usize {
    let mut i = 0;
    let mut j = v.len();
    while i < j {
        if left(v[i]) {
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
