//! Host side of glsl/trace/trace_query.comp: the trace interface as a kernel over a list of rays, for
//! tests (both trace paths must agree) and for `illum bench trace`.

use crate::error::Result;
use crate::gpu_scene::GpuScene;
use crate::layout::*;
use crate::shaders;
use crate::trace::TraceStructure;
use crate::vk::{Buffer, ComputePipeline, Context, GpuTimer, MemoryLocation};
use ash::vk;
use std::time::Instant;

pub use crate::layout::{QueryHit as HitRecord, QueryRay as Ray};

/// Rays per submission, so that no dispatch runs long on slow devices.
const RAYS_PER_SUBMIT: usize = 1 << 18;
const GROUP: u32 = 64;

impl Ray {
    pub fn new(origin: [f32; 3], dir: [f32; 3], tmin: f32, tmax: f32, mask: u32) -> Ray {
        Ray {
            origin,
            tmin,
            dir,
            tmax,
            mask,
            ..Default::default()
        }
    }
}

/// The trace_query kernel built for one scene and trace structure.
pub struct QueryKernel {
    pipeline: ComputePipeline,
    _frame: Buffer,
}

impl QueryKernel {
    pub fn new(ctx: &Context, scene: &GpuScene, trace: &TraceStructure) -> Result<QueryKernel> {
        let frame = ctx.upload(
            "frame",
            std::slice::from_ref(&scene.frame),
            vk::BufferUsageFlags::UNIFORM_BUFFER,
        )?;
        let mut bindings = vec![(BINDING_FRAME, vk::DescriptorType::UNIFORM_BUFFER)];
        bindings.extend(trace.bindings());
        let pipeline = ComputePipeline::new(
            ctx,
            "trace_query",
            trace.select(shaders::TRACE_QUERY_RQ, shaders::TRACE_QUERY_BVH),
            &bindings,
            std::mem::size_of::<QueryConstants>() as u32,
            &[scene.features, scene.flat_kinds],
        )?;
        pipeline.bind_buffer(BINDING_FRAME, vk::DescriptorType::UNIFORM_BUFFER, &frame);
        trace.bind(&pipeline);
        Ok(QueryKernel {
            pipeline,
            _frame: frame,
        })
    }

    /// Traces `rays` with `mode` (QUERY_CLOSEST and/or QUERY_OCCLUDED; fields of the other stay
    /// at their miss values). Returns one record per ray, the wall seconds the submissions took
    /// (uploads and readback excluded) and, where the queue has timestamps, the device seconds
    /// of the dispatches alone (without submission and fence waits, which dominate small
    /// batches on a GPU).
    pub fn trace(
        &self,
        ctx: &Context,
        rays: &[Ray],
        mode: u32,
    ) -> Result<(Vec<HitRecord>, f64, Option<f64>)> {
        if rays.is_empty() {
            return Ok((Vec::new(), 0.0, None));
        }
        let timer = GpuTimer::new(ctx)?;
        let mut device = timer.as_ref().map(|_| 0.0);
        let ray_buffer = ctx.upload("query rays", rays, vk::BufferUsageFlags::STORAGE_BUFFER)?;
        let hit_buffer = ctx.create_buffer(
            "query hits",
            std::mem::size_of_val(rays) as u64 / std::mem::size_of::<Ray>() as u64
                * std::mem::size_of::<HitRecord>() as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
        )?;
        let mut seconds = 0.0;
        for first in (0..rays.len()).step_by(RAYS_PER_SUBMIT) {
            let count = (rays.len() - first).min(RAYS_PER_SUBMIT) as u32;
            let pc = QueryConstants {
                rays: ray_buffer.address + (first * std::mem::size_of::<Ray>()) as u64,
                hits: hit_buffer.address + (first * std::mem::size_of::<HitRecord>()) as u64,
                count,
                mode,
            };
            let t = Instant::now();
            ctx.one_shot(|cmd| {
                GpuTimer::around(timer.as_ref(), cmd, || {
                    self.pipeline.dispatch(
                        cmd,
                        bytemuck::bytes_of(&pc),
                        [count.div_ceil(GROUP), 1, 1],
                    )
                })
            })?;
            seconds += t.elapsed().as_secs_f64();
            if let (Some(t), Some(d)) = (&timer, device.as_mut()) {
                *d += t.seconds()?;
            }
        }
        Ok((ctx.download(&hit_buffer, rays.len())?, seconds, device))
    }
}

/// Closest hit and occlusion of every ray against `trace` (built over `scene`).
pub fn trace_rays(
    ctx: &Context,
    scene: &GpuScene,
    trace: &TraceStructure,
    rays: &[Ray],
) -> Result<Vec<HitRecord>> {
    let kernel = QueryKernel::new(ctx, scene, trace)?;
    Ok(kernel.trace(ctx, rays, QUERY_CLOSEST | QUERY_OCCLUDED)?.0)
}
