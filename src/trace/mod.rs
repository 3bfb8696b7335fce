//! Trace structures behind the one GLSL trace interface (glsl/trace/trace.glsl): hardware ray
//! queries (acceleration structures) or illum's compute BVH.

pub mod bench;
pub mod bvh;
pub mod query;
pub mod rayquery;

use crate::error::{Error, Result};
use crate::gpu_scene::GpuScene;
use crate::layout::*;
use crate::vk::{ComputePipeline, Context};
use ash::vk;
use rayquery::{AabbGeometry, BlasInput, RayQueryScene, TlasInstance, TriangleGeometry};

/// Which implementation of the trace interface a render uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum TraceMode {
    /// Ray queries when the device has them, else the compute BVH.
    #[default]
    Auto,
    RayQuery,
    Bvh,
}

impl std::str::FromStr for TraceMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(TraceMode::Auto),
            "rayquery" => Ok(TraceMode::RayQuery),
            "bvh" => Ok(TraceMode::Bvh),
            _ => Err(format!(
                "unknown trace mode {s:?} (expected auto, rayquery or bvh)"
            )),
        }
    }
}

/// What building a trace structure took: time and memory.
///
/// Ray queries: bottom levels are the compacted BLASes, the top level is the TLAS. Compute BVH:
/// bottom levels are every mesh's nodes plus its triangles in leaf order, the top level is its
/// nodes plus the instance records; `blas_seconds` is the host build of the bottom levels,
/// `tlas_seconds` the top level plus the upload.
#[derive(Clone, Debug, Default)]
pub struct BuildStats {
    pub blas_count: usize,
    pub triangles: u64,
    pub blas_bytes_uncompacted: u64,
    pub blas_bytes: u64,
    pub tlas_bytes: u64,
    pub scratch_bytes: u64,
    pub blas_seconds: f64,
    pub compaction_seconds: f64,
    pub tlas_seconds: f64,
    /// Compute BVH: the deepest traversal stack a ray may need.
    pub max_stack: u32,
}

impl BuildStats {
    pub fn seconds(&self) -> f64 {
        self.blas_seconds + self.compaction_seconds + self.tlas_seconds
    }

    pub fn bytes(&self) -> u64 {
        self.blas_bytes + self.tlas_bytes
    }
}

/// The trace structure a kernel binds.
// One per prepared scene, never copied around: the variants' size difference does not matter.
#[allow(clippy::large_enum_variant)]
pub enum TraceStructure {
    RayQuery(RayQueryScene),
    Bvh(bvh::BvhScene),
}

impl TraceStructure {
    /// Builds the structure `mode` asks for over an uploaded scene.
    pub fn build(ctx: &Context, scene: &GpuScene, mode: TraceMode) -> Result<TraceStructure> {
        match mode.resolve(ctx)? {
            TraceMode::RayQuery => Self::build_ray_query(ctx, scene),
            _ => Ok(TraceStructure::Bvh(bvh::build(ctx, scene)?)),
        }
    }

    /// Short name for reports: "rayquery" or "bvh".
    pub fn name(&self) -> &'static str {
        match self {
            TraceStructure::RayQuery(_) => "rayquery",
            TraceStructure::Bvh(_) => "bvh",
        }
    }

    /// The SPIR-V variant of a kernel for this structure.
    pub fn select<'a>(&self, rq: &'a [u8], bvh: &'a [u8]) -> &'a [u8] {
        match self {
            TraceStructure::RayQuery(_) => rq,
            TraceStructure::Bvh(_) => bvh,
        }
    }

    /// Descriptor bindings the trace interface needs (beside the kernel's own).
    pub fn bindings(&self) -> Vec<(u32, vk::DescriptorType)> {
        match self {
            TraceStructure::RayQuery(_) => {
                vec![(BINDING_TLAS, vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)]
            }
            TraceStructure::Bvh(_) => vec![(BINDING_BVH, vk::DescriptorType::UNIFORM_BUFFER)],
        }
    }

    pub fn bind(&self, pipeline: &ComputePipeline) {
        match self {
            TraceStructure::RayQuery(rq) => {
                pipeline.bind_acceleration_structure(BINDING_TLAS, rq.tlas.handle)
            }
            TraceStructure::Bvh(b) => {
                pipeline.bind_buffer(BINDING_BVH, vk::DescriptorType::UNIFORM_BUFFER, &b.header)
            }
        }
    }

    pub fn build_stats(&self) -> &BuildStats {
        match self {
            TraceStructure::RayQuery(rq) => &rq.stats,
            TraceStructure::Bvh(b) => &b.stats,
        }
    }

    /// Builds the ray-query acceleration structures over an uploaded scene.
    pub fn build_ray_query(ctx: &Context, scene: &GpuScene) -> Result<TraceStructure> {
        let mut inputs = Vec::new();
        if let (Some(vb), Some(ib)) = (&scene.vertex_buffer, &scene.index_buffer) {
            for m in &scene.meshes {
                inputs.push(BlasInput::Triangles(TriangleGeometry {
                    vertex_address: vb.address
                        + u64::from(m.first_vertex) * std::mem::size_of::<GpuVertex>() as u64,
                    vertex_stride: std::mem::size_of::<GpuVertex>() as u64,
                    vertex_count: m.vertex_count,
                    index_address: ib.address + u64::from(m.first_index) * 4,
                    triangle_count: m.triangle_count,
                }));
            }
        }
        if let Some(ab) = &scene.aabb_buffer {
            for (first, count, _) in shape_runs(scene) {
                inputs.push(BlasInput::Aabbs(AabbGeometry {
                    aabb_address: ab.address + first as u64 * 24,
                    count: count as u32,
                }));
            }
        }
        Ok(TraceStructure::RayQuery(rayquery::build(
            ctx,
            &inputs,
            &top_instances(scene),
        )?))
    }

    /// Follows moved instances of `scene` (the one the structure was built over, updated by
    /// `GpuScene::update`): the top level is built again, the bottom levels are kept.
    pub fn update_top(&mut self, ctx: &Context, scene: &GpuScene) -> Result<f64> {
        match self {
            TraceStructure::RayQuery(rq) => rq.update_top(ctx, &top_instances(scene)),
            TraceStructure::Bvh(b) => b.update_top(ctx, scene),
        }
    }
}

/// Runs of consecutive shapes that share a ray mask: (first, count, mask). Each is one AABB
/// bottom level.
fn shape_runs(scene: &GpuScene) -> Vec<(usize, usize, u32)> {
    let masks = &scene.shape_masks;
    let mut runs = Vec::new();
    let mut first = 0;
    while first < masks.len() {
        let mask = masks[first];
        let count = masks[first..].iter().take_while(|&&m| m == mask).count();
        runs.push((first, count, mask));
        first += count;
    }
    runs
}

/// The ray-query top level: mesh instances (bottom level = mesh index), then one identity
/// instance per run of shapes (bottom levels after the meshes').
fn top_instances(scene: &GpuScene) -> Vec<TlasInstance> {
    let identity = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
    ];
    let mut instances = Vec::new();
    let meshes = if scene.vertex_buffer.is_some() && scene.index_buffer.is_some() {
        for (i, (mesh, rows)) in scene.instances.iter().enumerate() {
            instances.push(TlasInstance {
                blas: *mesh as usize,
                transform: *rows,
                custom_index: i as u32,
                mask: MASK_GEOMETRY as u8,
            });
        }
        scene.meshes.len()
    } else {
        0
    };
    if scene.aabb_buffer.is_some() {
        for (k, (first, _, mask)) in shape_runs(scene).into_iter().enumerate() {
            instances.push(TlasInstance {
                blas: meshes + k,
                transform: identity,
                custom_index: first as u32,
                mask: mask as u8,
            });
        }
    }
    instances
}

impl TraceMode {
    /// The concrete path for this device: `Auto` takes ray queries when the device has them,
    /// except where illum's BVH is measured faster (see [`bvh_is_faster`]).
    pub fn resolve(self, ctx: &Context) -> Result<TraceMode> {
        match self {
            TraceMode::Auto if ctx.ray_query() && !bvh_is_faster(ctx.info()) => {
                Ok(TraceMode::RayQuery)
            }
            TraceMode::Auto => Ok(TraceMode::Bvh),
            TraceMode::RayQuery if !ctx.ray_query() => {
                Err(Error::Gpu(crate::vk::Error::Unsupported {
                    device: ctx.info().name.clone(),
                    what: "--trace rayquery was asked for, but the device has no VK_KHR_ray_query"
                        .into(),
                }))
            }
            m => Ok(m),
        }
    }
}

/// Devices whose ray queries are slower than illum's compute BVH.
///
/// Lavapipe (Mesa's llvmpipe Vulkan driver): its ray queries are a software traversal too, and
/// `illum bench trace` on Mesa 25.0.7 (2 cores) measured the BVH 4-8× faster on camera rays and
/// 3-10× on incoherent bounce rays, at 100k and 1M triangles (figures in src/trace/bvh/mod.rs).
/// GPUs with ray-tracing hardware keep ray queries.
pub fn bvh_is_faster(info: &crate::vk::DeviceInfo) -> bool {
    info.driver_id == vk::DriverId::MESA_LLVMPIPE
}
