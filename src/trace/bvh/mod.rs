//! illum's compute BVH: the trace structure for devices without ray queries, and for those where
//! it is faster (see `TraceMode::resolve`).
//!
//! - Build (host, parallel): a binned-SAH binary tree per mesh over its triangles
//!   ([`builder`]), a top-level tree over the instances (with their transforms) and the analytic
//!   shapes, each collapsed into 4-wide nodes with 8-bit quantized child boxes ([`nodes`]).
//! - Memory: one array of nodes (every bottom level, then the top level), the triangles'
//!   vertices gathered in leaf order (no index indirection at trace time), and the top-level
//!   leaves; the kernels reach them through buffer device addresses held in a small uniform
//!   buffer at `BINDING_BVH`, so no binding limit (128 MiB on lavapipe) applies.
//! - Traversal: glsl/trace/bvh.glsl.
//!
//! # Why this layout: measurements
//!
//! Lavapipe (Mesa 25.0.7, AVX2, 8 lanes) turns every load from a per-lane address into 8 scalar
//! loads and runs every branch of a loop body under a mask, so the cost of a ray is mostly the
//! words it fetches, then the loop body's ALU. `illum bench trace`, one lavapipe thread
//! (LP_NUM_THREADS=1), Mrays per CPU-second, best of 6 runs of 65536 rays, on a shared 2-core
//! machine (±5 %); camera rays (closest hit) / bounce rays (any hit) / bounce rays (closest):
//!
//! | layout and loop                                    | 100k triangles     | 1M triangles       |
//! |----------------------------------------------------|--------------------|--------------------|
//! | ray queries (lavapipe's own BVH)                   | 0.19 / 0.16 / 0.15 | 0.09 / 0.07 / 0.07 |
//! | BVH4, f32 boxes in SoA (112 B), leaf loop          | 0.41 / 0.28 / 0.24 | 0.35 / 0.23 / 0.20 |
//! | same, one triangle per loop iteration              | 0.50 / 0.35 / 0.30 | 0.44 / 0.28 / 0.25 |
//! | BVH2, f32 boxes (64 B, 14 words)                   | 0.62 / 0.41 / 0.37 | 0.53 / 0.34 / 0.30 |
//! | BVH4, 8-bit quantized boxes (64 B, 14 words)       | 0.72 / 0.54 / 0.45 | 0.62 / 0.44 / 0.38 |
//! | + entry distances on the stack (closest hit)       | 0.86 / 0.53 / 0.50 | 0.74 / 0.44 / 0.41 |
//! | + near/far planes chosen by direction signs (used) | 0.90 / 0.53 / 0.51 | 0.75 / 0.44 / 0.43 |
//!
//! Per camera ray, BVH2 visits 24 nodes in 28 loop iterations, BVH4 13 nodes in 18 (3 triangles
//! either way); 8-lane SIMD efficiency is 80 % on camera rays, 65 % on bounce rays. Quantizing
//! halves a 4-wide node's words and costs almost no extra visits, which is what made 4-wide win.
//! Tried and dropped (same conditions): separate loops for the two levels (-5 to -15 %), two node
//! steps per iteration (-13 %), the stack in shared memory (-3 %), popping until an entry is in
//! range (-15 %), leaves of 2 or 8 triangles and SAH traversal costs 0.5 to 3 (no gain or worse).
//! A 4-wide node with compressed links (13 words) would save one word per node for about as much
//! decoding ALU; 8-wide quantized nodes would fetch more words per ray than 4-wide (about 24 words
//! per node at roughly 9 to 10 visits against 14 at 13).
//!
//! The kernels read nodes, triangles (40 bytes: the vertices and the mesh
//! index, no padding) and instances as 64-bit words, two fields per load: 1.4-1.5x rays per
//! CPU-second where lavapipe loads lane by lane (Mesa 22; Mesa 25 without AVX-512), the same with
//! AVX-512 gathers, 12 % less BLAS memory. Figures, profile and what was dropped:
//! docs/performance-kernels.md, "Trace throughput".

pub mod builder;
pub mod nodes;

use super::BuildStats;
use crate::error::{Error, Result};
use crate::gpu_scene::GpuScene;
use crate::layout::*;
use crate::vk::{Buffer, Context};
use ash::vk;
use builder::{Aabb, BuildParams};
use bytemuck::Zeroable;
use glam::{DMat4, DVec3, DVec4, Vec3A};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// The compute BVH of a scene, in device memory.
pub struct BvhScene {
    /// Uniform buffer holding the `BvhHeader` (bound at `BINDING_BVH`).
    pub header: Buffer,
    header_data: BvhHeader,
    nodes: Buffer,
    _triangles: Buffer,
    instances: Buffer,
    /// The bottom levels, for rebuilding the top level alone.
    bottoms: Vec<Bottom>,
    blas_nodes: usize,
    /// Nodes reserved for the top level after the bottom levels' `blas_nodes`.
    top_capacity: usize,
    pub stats: BuildStats,
}

/// One mesh's bottom level: nodes with local links, triangles in leaf order.
struct MeshBvh {
    nodes: Vec<BvhNode>,
    triangles: Vec<BvhTriangle>,
    root: u32,
    need: u32,
    bounds: Aabb,
}

/// Meshes with at least this many triangles are built one at a time on every thread; smaller
/// ones are spread over the threads, one mesh each.
const LARGE_MESH: usize = 1 << 16;

fn params(threads: usize) -> BuildParams {
    BuildParams {
        max_leaf: 4,
        traversal_cost: 1.0,
        threads,
        ..Default::default()
    }
}

/// A mesh's tree over its triangles' boxes: SAH (`slack` None), or within `slack` levels of a
/// balanced tree and collapsed two levels a wide node, so that a walk's stack stays bounded.
/// Returns the binary tree, its wide nodes, the root link and the stack a walk needs.
fn mesh_tree(
    boxes: &[Aabb],
    threads: usize,
    slack: Option<u32>,
) -> (builder::BinaryBvh, Vec<BvhNode>, u32, u32) {
    let base = params(threads);
    let max_depth = slack.map_or(u32::MAX, |k| {
        builder::balanced_depth(boxes.len(), base.max_leaf).saturating_add(k)
    });
    let bin = builder::build(boxes, &BuildParams { max_depth, ..base });
    let open = match slack {
        None => nodes::Open::LargestArea,
        Some(_) => nodes::Open::Shallowest,
    };
    let mut nodes = Vec::new();
    let (root, need) = nodes::collapse_as(&bin, &mut nodes, &|_, _| 0, open);
    (bin, nodes, root, need)
}

fn build_mesh(scene: &GpuScene, mesh: usize, threads: usize, slack: Option<u32>) -> MeshBvh {
    let m = scene.meshes[mesh];
    let pos = &scene.positions[m.first_vertex as usize..(m.first_vertex + m.vertex_count) as usize];
    let idx =
        &scene.indices[m.first_index as usize..(m.first_index + 3 * m.triangle_count) as usize];
    let corners =
        |t: usize| -> [Vec3A; 3] { [0, 1, 2].map(|k| Vec3A::from(pos[idx[3 * t + k] as usize])) };
    let boxes: Vec<Aabb> = (0..m.triangle_count as usize)
        .map(|t| Aabb::from_points(&corners(t)))
        .collect();
    let (bin, nodes, root, need) = mesh_tree(&boxes, threads, slack);
    let triangles = bin
        .order
        .iter()
        .map(|&t| {
            let [a, b, c] = corners(t as usize);
            let ([x0, y0, z0], [x1, y1, z1], [x2, y2, z2]) =
                (a.to_array(), b.to_array(), c.to_array());
            BvhTriangle {
                x0,
                y0,
                z0,
                x1,
                y1,
                z1,
                x2,
                y2,
                z2,
                prim: t,
            }
        })
        .collect();
    MeshBvh {
        nodes,
        triangles,
        root,
        need,
        bounds: bin.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds),
    }
}

/// Builds every mesh's bottom level: large meshes in turn with all threads, then the small ones
/// spread over the threads.
fn build_meshes(scene: &GpuScene, threads: usize) -> Vec<MeshBvh> {
    let n = scene.meshes.len();
    let slots: Vec<Mutex<Option<MeshBvh>>> = (0..n).map(|_| Mutex::new(None)).collect();
    let (large, small): (Vec<usize>, Vec<usize>) =
        (0..n).partition(|&i| scene.meshes[i].triangle_count as usize >= LARGE_MESH);
    for &i in &large {
        *slots[i].lock().unwrap() = Some(build_mesh(scene, i, threads, None));
    }
    let next = AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..threads.min(small.len()) {
            s.spawn(|| {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&i) = small.get(k) else { break };
                    let b = build_mesh(scene, i, 1, None);
                    *slots[i].lock().unwrap() = Some(b);
                }
            });
        }
    });
    slots
        .into_iter()
        .map(|s| s.into_inner().unwrap().expect("every mesh was built"))
        .collect()
}

/// The world-space box of an object-space box under a 3x4 transform, padded so that the box test
/// in world space never rejects a ray that hits in object space.
fn transform_box(b: &Aabb, rows: &[[f32; 4]; 3]) -> Aabb {
    let m = rows_to_mat(rows);
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for k in 0..8 {
        let p = DVec3::new(
            f64::from(if k & 1 == 0 { b.lo.x } else { b.hi.x }),
            f64::from(if k & 2 == 0 { b.lo.y } else { b.hi.y }),
            f64::from(if k & 4 == 0 { b.lo.z } else { b.hi.z }),
        );
        let q = m.transform_point3(p);
        lo = lo.min(q);
        hi = hi.max(q);
    }
    let pad = (hi - lo) * 1e-5 + (lo.abs().max(hi.abs())) * 1e-6 + DVec3::splat(1e-6);
    let (lo, hi) = (lo - pad, hi + pad);
    Aabb {
        lo: Vec3A::new(lo.x as f32, lo.y as f32, lo.z as f32),
        hi: Vec3A::new(hi.x as f32, hi.y as f32, hi.z as f32),
    }
}

fn rows_to_mat(rows: &[[f32; 4]; 3]) -> DMat4 {
    let r = |i: usize| DVec4::from_array(rows[i].map(f64::from));
    DMat4::from_cols(r(0), r(1), r(2), DVec4::new(0.0, 0.0, 0.0, 1.0)).transpose()
}

/// Rows of the inverse of a 3x4 object-to-world transform, or None when it is singular.
fn inverse_rows(rows: &[[f32; 4]; 3]) -> Option<[[f32; 4]; 3]> {
    let m = rows_to_mat(rows);
    let det = m.determinant();
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = m.inverse();
    let out = [0, 1, 2].map(|i| inv.row(i).to_array().map(|v| v as f32));
    out.iter().flatten().all(|v| v.is_finite()).then_some(out)
}

/// Builds the compute BVH over an uploaded scene.
pub fn build(ctx: &Context, scene: &GpuScene) -> Result<BvhScene> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let t0 = Instant::now();
    let mut meshes = build_meshes(scene, threads);
    // A walk must fit the kernels' stack (BVH_STACK_SIZE). SAH trees of degenerate inputs (a
    // million random or identical triangles) can be deeper: their meshes are built again with a
    // binary depth of at most `slack` levels past a balanced tree, then balanced outright, which
    // fits any mesh the BVH can hold: 22 levels for 2^24 triangles, collapsed two levels a wide
    // node (nodes::Open::Shallowest), a walk of at most 33 entries.
    let top_reserve = top_level_need(scene);
    for slack in [8, 0] {
        if meshes
            .iter()
            .all(|m| m.need + top_reserve <= BVH_STACK_SIZE)
        {
            break;
        }
        for (i, m) in meshes.iter_mut().enumerate() {
            if m.need + top_reserve > BVH_STACK_SIZE {
                *m = build_mesh(scene, i, threads, Some(slack));
            }
        }
    }
    let blas_seconds = t0.elapsed().as_secs_f64();

    // Concatenate the bottom levels.
    let t1 = Instant::now();
    let mut nodes: Vec<BvhNode> = Vec::new();
    let mut triangles: Vec<BvhTriangle> = Vec::new();
    let mut roots = Vec::with_capacity(meshes.len());
    for m in &meshes {
        let (node_offset, prim_offset) = (nodes.len() as u32, triangles.len() as u32);
        if triangles.len() + m.triangles.len() > BVH_LEAF_FIRST_MASK as usize {
            return Err(Error::Gpu(crate::vk::Error::Unsupported {
                device: ctx.info().name.clone(),
                what: format!(
                    "the compute BVH holds at most {} triangles",
                    BVH_LEAF_FIRST_MASK
                ),
            }));
        }
        nodes.extend(m.nodes.iter().map(|n| {
            BvhNode {
                links: n
                    .links
                    .map(|l| nodes::offset_link(l, node_offset, prim_offset)),
                ..*n
            }
        }));
        triangles.extend_from_slice(&m.triangles);
        roots.push(nodes::offset_link(m.root, node_offset, prim_offset));
    }
    let blas_nodes = nodes.len();

    let bottoms: Vec<Bottom> = meshes
        .iter()
        .zip(&roots)
        .map(|(m, &root)| Bottom {
            root,
            need: m.need,
            bounds: m.bounds,
            empty: m.root == NONE,
        })
        .collect();
    let (top_nodes, instances, root, need) = top_level(scene, &bottoms, nodes.len() as u32)?;
    // Room for the largest top level the instances can have (one 4-wide node per binary inner
    // node at most, and a root), so that moving them rewrites it in place.
    let items = scene.instances.len() + scene.shapes.len();
    let top_capacity = (items + 1).max(top_nodes.len());
    nodes.extend(top_nodes);
    nodes.resize(blas_nodes + top_capacity, BvhNode::default());
    let mut instances_padded = instances.clone();
    instances_padded.resize(items.max(1), BvhInstance::default());
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let node_buffer = ctx.upload("BVH nodes", &nodes, storage)?;
    let triangle_buffer = ctx.upload("BVH triangles", &triangles, storage)?;
    let instance_buffer = ctx.upload("BVH instances", &instances_padded, storage)?;
    let header = BvhHeader {
        nodes: node_buffer.address,
        triangles: triangle_buffer.address,
        instances: instance_buffer.address,
        root,
        node_count: (blas_nodes + top_capacity) as u32,
    };
    let flat = flat_shapes(scene);
    let header_buffer = ctx.upload_parts(
        "BVH header",
        &[bytemuck::bytes_of(&header), bytemuck::bytes_of(&flat)],
        vk::BufferUsageFlags::UNIFORM_BUFFER,
    )?;
    let node_size = std::mem::size_of::<BvhNode>() as u64;
    let blas_bytes = blas_nodes as u64 * node_size + std::mem::size_of_val(&triangles[..]) as u64;
    let stats = BuildStats {
        blas_count: meshes.len(),
        triangles: triangles.len() as u64,
        blas_bytes,
        blas_bytes_uncompacted: blas_bytes,
        tlas_bytes: (nodes.len() - blas_nodes) as u64 * node_size
            + std::mem::size_of_val(&instances_padded[..]) as u64,
        blas_seconds,
        tlas_seconds: t1.elapsed().as_secs_f64(),
        max_stack: need,
        ..Default::default()
    };
    ctx.count_builds(meshes.len(), 1);
    Ok(BvhScene {
        header: header_buffer,
        header_data: header,
        nodes: node_buffer,
        _triangles: triangle_buffer,
        instances: instance_buffer,
        bottoms,
        blas_nodes,
        top_capacity,
        stats,
    })
}

/// A bound on the stack a walk of the top level takes before it enters an instance: the top
/// level's own levels over all its items (a balanced bound, 3 entries per 4-wide level, doubled
/// for SAH's imbalance, at least 4) and the entry marking the instance.
fn top_level_need(scene: &GpuScene) -> u32 {
    let items = scene.instances.len() + scene.shapes.len();
    let wide_levels = builder::balanced_depth(items, 1).div_ceil(2);
    (2 * 3 * wide_levels).max(4) + 1
}

/// What the top level needs of one mesh's bottom level.
struct Bottom {
    /// Root link, offset into the shared node array.
    root: u32,
    need: u32,
    bounds: Aabb,
    empty: bool,
}

/// The top level over instances of non-empty meshes with an invertible transform, then the
/// shapes: its nodes (links offset by `offset`, where they will sit in the node array), the
/// instance records in leaf order, the root link and the stack a walk needs.
fn top_level(
    scene: &GpuScene,
    bottoms: &[Bottom],
    offset: u32,
) -> Result<(Vec<BvhNode>, Vec<BvhInstance>, u32, u32)> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut items: Vec<(Aabb, BvhInstance, u32)> = Vec::new();
    for (i, (mesh, rows)) in scene.instances.iter().enumerate() {
        let m = &bottoms[*mesh as usize];
        let Some(inv) = inverse_rows(rows) else {
            continue;
        };
        if m.empty {
            continue;
        }
        let inst = BvhInstance {
            world_to_object: inv,
            root: m.root,
            index: i as u32,
            mask: MASK_GEOMETRY,
            pad: 0,
        };
        items.push((transform_box(&m.bounds, rows), inst, 1 + m.need));
    }
    for i in 0..scene.shapes.len() {
        let b = scene.shape_boxes[i];
        let inst = BvhInstance {
            root: BVH_SHAPE,
            index: i as u32,
            mask: scene.shape_masks[i],
            ..Default::default()
        };
        let aabb = Aabb {
            lo: Vec3A::new(b[0], b[1], b[2]),
            hi: Vec3A::new(b[3], b[4], b[5]),
        };
        items.push((aabb, inst, 0));
    }
    let boxes: Vec<Aabb> = items.iter().map(|i| i.0).collect();
    let top = builder::build(
        &boxes,
        &BuildParams {
            max_leaf: 1,
            ..params(threads)
        },
    );
    let instances: Vec<BvhInstance> = top.order.iter().map(|&k| items[k as usize].1).collect();
    let leaf_need = |first: u32, _| items[top.order[first as usize] as usize].2;
    let mut top_nodes = Vec::new();
    let (root, need) = nodes::collapse(&top, &mut top_nodes, &leaf_need);
    let top_nodes = top_nodes
        .iter()
        .map(|n| BvhNode {
            links: n.links.map(|l| nodes::offset_link(l, offset, 0)),
            ..*n
        })
        .collect();
    if need > BVH_STACK_SIZE {
        return Err(Error::Invalid(format!(
            "the compute BVH is too deep: a walk may need {need} stack entries, the kernels have \
             {BVH_STACK_SIZE}, even with every mesh balanced ({} instances and shapes in its top \
             level); --trace rayquery traces it where the device has ray queries",
            items.len()
        )));
    }
    Ok((
        top_nodes,
        instances,
        nodes::offset_link(root, offset, 0),
        need,
    ))
}

/// The first BVH_FLAT_MAX shapes with their ray masks and padded boxes, as FEATURE_FLAT_SHAPES
/// reads them after the header (zero where the scene has fewer; unread where it has more, which
/// the feature excludes).
fn flat_shapes(scene: &GpuScene) -> BvhFlat {
    let mut flat = BvhFlat::zeroed();
    for (i, (s, m)) in scene
        .shapes
        .iter()
        .zip(&scene.shape_masks)
        .take(BVH_FLAT_MAX as usize)
        .enumerate()
    {
        flat.shapes[i] = *s;
        flat.masks[i] = *m;
        let b = scene.shape_boxes[i];
        flat.lo[i] = [b[0], b[1], b[2], 0.0];
        flat.hi[i] = [b[3], b[4], b[5], 0.0];
    }
    flat
}

impl BvhScene {
    /// Builds the top level again over moved instances and writes it in place: the bottom
    /// levels (nodes and triangles) stay as they are on the device.
    pub fn update_top(&mut self, ctx: &Context, scene: &GpuScene) -> Result<f64> {
        let t = Instant::now();
        let (top, instances, root, need) = top_level(scene, &self.bottoms, self.blas_nodes as u32)?;
        if top.len() > self.top_capacity {
            return Err(Error::Invalid(format!(
                "the top level grew to {} nodes, past the {} reserved",
                top.len(),
                self.top_capacity
            )));
        }
        let node_size = std::mem::size_of::<BvhNode>() as u64;
        ctx.write(&self.nodes, self.blas_nodes as u64 * node_size, &top)?;
        ctx.write(&self.instances, 0, &instances)?;
        self.header_data.root = root;
        ctx.write(&self.header, 0, std::slice::from_ref(&self.header_data))?;
        // The flat copy of the shapes stays: an update cannot move a shape (PreparedScene::update).
        self.stats.max_stack = self.stats.max_stack.max(need);
        ctx.count_builds(0, 1);
        Ok(t.elapsed().as_secs_f64())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stack a walk of a mesh's tree needs, and its binary depth (build_mesh's tree).
    fn need(boxes: &[Aabb], slack: Option<u32>) -> (u32, u32) {
        let (bin, _, _, need) = mesh_tree(boxes, 2, slack);
        (need, binary_depth(&bin, 0))
    }

    fn binary_depth(bin: &builder::BinaryBvh, i: u32) -> u32 {
        let n = &bin.nodes[i as usize];
        if n.count > 0 {
            0
        } else {
            1 + binary_depth(bin, n.a).max(binary_depth(bin, n.b))
        }
    }

    /// Triangles with three uniformly random corners in a cube: boxes that overlap everywhere,
    /// the input that drove SAH trees past the kernels' stack.
    fn random_triangles(n: usize) -> Vec<Aabb> {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n)
            .map(|_| {
                let p: [Vec3A; 3] = std::array::from_fn(|_| Vec3A::new(next(), next(), next()));
                Aabb::from_points(&p)
            })
            .collect()
    }

    #[test]
    fn balanced_depth_is_the_median_trees_depth() {
        assert_eq!(builder::balanced_depth(0, 4), 0);
        assert_eq!(builder::balanced_depth(4, 4), 0);
        assert_eq!(builder::balanced_depth(5, 4), 1);
        assert_eq!(builder::balanced_depth(1 << 20, 4), 18);
        assert_eq!(builder::balanced_depth((1 << 20) + 1, 4), 19);
        for n in [1usize, 5, 17, 1000, 4097] {
            let boxes = random_triangles(n);
            assert!(
                need(&boxes, Some(0)).1 <= builder::balanced_depth(n, 4),
                "{n}"
            );
        }
    }

    /// Degenerate meshes: the depth bound holds by construction, and a balanced tree of any mesh
    /// the BVH can hold fits the kernels' stack with room for the top level.
    #[test]
    fn degenerate_meshes_fit_the_stack() {
        let same = vec![random_triangles(1)[0]; 300_000];
        for (name, boxes) in [("random", random_triangles(300_000)), ("identical", same)] {
            let (sah, sah_depth) = need(&boxes, None);
            let bound = builder::balanced_depth(boxes.len(), 4);
            for slack in [8, 0] {
                let (n, depth) = need(&boxes, Some(slack));
                crate::note!(
                    "{name}: SAH need {sah} (depth {sah_depth}); slack {slack}: need {n}, depth {depth} (bound {})",
                    bound + slack
                );
                assert!(
                    depth <= bound + slack,
                    "{name}, slack {slack}: depth {depth}"
                );
                assert!(
                    n <= 3 * depth.div_ceil(2),
                    "{name}, slack {slack}: need {n}"
                );
            }
        }
        // 2^24 triangles balanced: 22 binary levels, 11 wide ones of at most 3 pushes each.
        let widest = 3 * builder::balanced_depth(1 << 24, 4).div_ceil(2);
        assert!(widest + 8 <= BVH_STACK_SIZE, "{widest}");
    }
}
