//! The direct-lighting integrator (glsl/primary.comp, glsl/shared/direct.glsl): camera rays, the
//! AOVs, and emission plus direct lighting at the first hit, estimated as "Physically Based
//! Lighting at Pixar" does (TECHNIQUES.md §3).

use super::integrator::{Integrator, IntegratorPasses};
use super::{IntegratorSettings, LightSelection, PreparedScene, Technique};
use crate::error::Result;
use crate::gpu_scene::GpuScene;
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

/// Direct lighting with the course's sample counts and MIS.
pub struct Direct(pub IntegratorSettings);

impl Integrator for Direct {
    fn name(&self) -> &'static str {
        "direct"
    }

    fn configure(&self, frame: &mut Frame) {
        let it = &self.0;
        frame.technique = match it.technique {
            Technique::Brdf => TECHNIQUE_BRDF,
            Technique::Light => TECHNIQUE_LIGHT,
            Technique::Mis => TECHNIQUE_MIS,
        };
        frame.light_samples = it.light_samples;
        frame.brdf_samples = it.brdf_samples;
        frame.integrator_flags = if it.diffuse_mis {
            INTEGRATOR_DIFFUSE_MIS
        } else {
            0
        };
        // Without finite lights there is no tree: the (infinite) lights are looped over.
        frame.light_select = match it.light_selection {
            LightSelection::Tree if frame.light_tree != 0 => LIGHT_SELECT_TREE,
            LightSelection::Scan => LIGHT_SELECT_SCAN,
            _ => LIGHT_SELECT_LOOP,
        };
    }

    fn kernels(
        &self,
        ctx: &Context,
        scene: &PreparedScene,
        frame: &Buffer,
        film: &Buffer,
    ) -> Result<Box<dyn IntegratorPasses>> {
        Ok(Box::new(PrimaryKernel::new(
            ctx,
            &scene.gpu,
            &scene.trace,
            frame,
            film,
        )?))
    }
}

impl IntegratorPasses for PrimaryKernel {
    fn bind(&self, frame: &Buffer, film: &Buffer) {
        self.pipeline
            .bind_buffer(BINDING_FRAME, vk::DescriptorType::UNIFORM_BUFFER, frame);
        self.pipeline
            .bind_buffer(BINDING_FILM, vk::DescriptorType::STORAGE_BUFFER, film);
    }

    fn record(&self, cmd: vk::CommandBuffer, pass: &PassConstants) {
        PrimaryKernel::record(self, cmd, pass);
    }
}
