//! Host side of glsl/primary.comp: primary rays, AOVs and the preview beauty.

use super::upload::GpuScene;
use crate::error::Result;
use crate::layout::*;
use crate::shaders;
use crate::trace::rayquery::{
    AabbGeometry, BlasInput, RayQueryScene, TlasInstance, TriangleGeometry,
};
use crate::vk::{Buffer, ComputePipeline, Context};
use ash::vk;

/// The trace structure a kernel binds.
pub enum TraceStructure {
    RayQuery(RayQueryScene),
}

impl TraceStructure {
    /// Builds the ray-query acceleration structures over an uploaded scene.
    pub fn build_ray_query(ctx: &Context, scene: &GpuScene) -> Result<TraceStructure> {
        let mut inputs = Vec::new();
        let mut instances = Vec::new();
        let identity = [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ];
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
            for (i, (mesh, rows)) in scene.instances.iter().enumerate() {
                instances.push(TlasInstance {
                    blas: *mesh as usize,
                    transform: *rows,
                    custom_index: i as u32,
                    mask: MASK_GEOMETRY as u8,
                });
            }
        }
        if let Some(ab) = &scene.aabb_buffer {
            let n = scene.shapes.len() as u32;
            let groups = [
                (0, scene.geometry_shapes, MASK_GEOMETRY),
                (
                    scene.geometry_shapes,
                    n - scene.geometry_shapes,
                    MASK_LIGHTS,
                ),
            ];
            for (first, count, mask) in groups {
                if count == 0 {
                    continue;
                }
                instances.push(TlasInstance {
                    blas: inputs.len(),
                    transform: identity,
                    custom_index: first,
                    mask: mask as u8,
                });
                inputs.push(BlasInput::Aabbs(AabbGeometry {
                    aabb_address: ab.address + u64::from(first) * 24,
                    count,
                }));
            }
        }
        Ok(TraceStructure::RayQuery(crate::trace::rayquery::build(
            ctx, &inputs, &instances,
        )?))
    }
}

pub struct PrimaryKernel {
    pipeline: ComputePipeline,
}

impl PrimaryKernel {
    pub fn new(
        ctx: &Context,
        scene: &GpuScene,
        trace: &TraceStructure,
        frame: &Buffer,
        film: &Buffer,
    ) -> Result<PrimaryKernel> {
        let TraceStructure::RayQuery(rq) = trace;
        let pipeline = ComputePipeline::new(
            ctx,
            "primary",
            shaders::PRIMARY_RQ,
            &[
                (BINDING_FRAME, vk::DescriptorType::UNIFORM_BUFFER),
                (BINDING_FILM, vk::DescriptorType::STORAGE_BUFFER),
                (BINDING_TLAS, vk::DescriptorType::ACCELERATION_STRUCTURE_KHR),
            ],
            std::mem::size_of::<PassConstants>() as u32,
            &[scene.features],
        )?;
        pipeline.bind_buffer(BINDING_FRAME, vk::DescriptorType::UNIFORM_BUFFER, frame);
        pipeline.bind_buffer(BINDING_FILM, vk::DescriptorType::STORAGE_BUFFER, film);
        pipeline.bind_acceleration_structure(BINDING_TLAS, rq.tlas.handle);
        Ok(PrimaryKernel { pipeline })
    }

    pub fn record(&self, cmd: vk::CommandBuffer, pass: &PassConstants) {
        let groups = [
            pass.tile[2].div_ceil(WORKGROUP_X),
            pass.tile[3].div_ceil(WORKGROUP_Y),
            1,
        ];
        self.pipeline
            .dispatch(cmd, bytemuck::bytes_of(pass), groups);
    }
}
