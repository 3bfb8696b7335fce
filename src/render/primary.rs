//! Host side of glsl/primary.comp: primary rays, AOVs and the preview beauty.

use super::upload::GpuScene;
use crate::error::Result;
use crate::layout::*;
use crate::shaders;
use crate::trace::TraceStructure;
use crate::vk::{Buffer, ComputePipeline, Context};
use ash::vk;

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
        let mut bindings = vec![
            (BINDING_FRAME, vk::DescriptorType::UNIFORM_BUFFER),
            (BINDING_FILM, vk::DescriptorType::STORAGE_BUFFER),
        ];
        bindings.extend(trace.bindings());
        let pipeline = ComputePipeline::new(
            ctx,
            "primary",
            trace.select(shaders::PRIMARY_RQ, shaders::PRIMARY_BVH),
            &bindings,
            std::mem::size_of::<PassConstants>() as u32,
            &[scene.features],
        )?;
        pipeline.bind_buffer(BINDING_FRAME, vk::DescriptorType::UNIFORM_BUFFER, frame);
        pipeline.bind_buffer(BINDING_FILM, vk::DescriptorType::STORAGE_BUFFER, film);
        trace.bind(&pipeline);
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
