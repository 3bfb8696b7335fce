//! The direct-lighting integrator (glsl/direct/primary.comp, glsl/direct/direct.glsl): camera rays, the
//! AOVs, and emission plus direct lighting at the first hit, estimated as "Physically Based
//! Lighting at Pixar" does (docs/techniques.md, "The direct-lighting estimator").

use super::integrator::{Integrator, IntegratorPasses};
use super::{ControlVariates, IntegratorSettings, LightSelection, PreparedScene, Technique};
use crate::error::Result;
use crate::layout::*;
use crate::shaders;
use crate::vk::{Buffer, ComputePipeline, Context};
use ash::vk;

pub struct PrimaryKernel {
    pipeline: ComputePipeline,
}

impl PrimaryKernel {
    pub fn new(ctx: &Context, scene: &PreparedScene, features: u32) -> Result<PrimaryKernel> {
        let pipeline = film_pipeline(
            ctx,
            scene,
            features,
            "primary",
            (shaders::PRIMARY_RQ, shaders::PRIMARY_BVH),
            false,
            std::mem::size_of::<PassConstants>(),
        )?;
        Ok(PrimaryKernel { pipeline })
    }
}

/// Direct lighting with the course's sample counts and MIS.
pub struct Direct(pub IntegratorSettings);

impl Integrator for Direct {
    fn name(&self) -> &'static str {
        "direct"
    }

    fn configure(&self, frame: &mut Frame) {
        configure_direct(&self.0, frame);
    }

    fn kernels(&self, ctx: &Context, scene: &PreparedScene) -> Result<Box<dyn IntegratorPasses>> {
        Ok(Box::new(PrimaryKernel::new(
            ctx,
            scene,
            self.0.kernel_features(),
        )?))
    }

    fn features(&self) -> u32 {
        self.0.kernel_features()
    }
}

impl IntegratorPasses for PrimaryKernel {
    fn bind(&self, frame: &Buffer, film: &Buffer, aovs: Option<&Buffer>) {
        bind_film(&self.pipeline, frame, film, aovs);
    }

    fn record(&self, cmd: vk::CommandBuffer, pass: &PassConstants) {
        dispatch_tile(&self.pipeline, cmd, pass);
    }
}

/// The direct-lighting settings every integrator shares (its camera hits are lit the same way).
pub fn configure_direct(it: &IntegratorSettings, frame: &mut Frame) {
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
    frame.shadow_resample = it.shadow_resample;
    frame.shadow_cull = it.shadow_cull;
    frame.control_variates = match it.control_variates {
        ControlVariates::Off => 0,
        ControlVariates::AvgVis => CONTROL_VARIATES_AVGVIS,
        ControlVariates::Loo => CONTROL_VARIATES_LOO,
    };
    // Without finite lights there is no tree: the (infinite) lights are looped over.
    frame.light_select = match it.light_selection {
        LightSelection::Tree if frame.light_tree != 0 => LIGHT_SELECT_TREE,
        LightSelection::Scan => LIGHT_SELECT_SCAN,
        _ => LIGHT_SELECT_LOOP,
    };
}

/// A kernel over film pixels (frame constants, film, the AOV planes if `aovs`, the trace
/// structure), with the scene's feature switches and `features` (the settings' own), taking
/// `push_size` bytes of push constants (PassConstants, or a struct that begins with them).
pub fn film_pipeline(
    ctx: &Context,
    scene: &PreparedScene,
    features: u32,
    name: &str,
    (rq, bvh): (&'static [u8], &'static [u8]),
    aovs: bool,
    push_size: usize,
) -> Result<ComputePipeline> {
    let mut bindings = vec![
        (BINDING_FRAME, vk::DescriptorType::UNIFORM_BUFFER),
        (BINDING_FILM, vk::DescriptorType::STORAGE_BUFFER),
    ];
    if aovs {
        bindings.push((BINDING_AOVS, vk::DescriptorType::STORAGE_BUFFER));
    }
    bindings.extend(scene.trace.bindings());
    let pipeline = ComputePipeline::new(
        ctx,
        name,
        scene.trace.select(rq, bvh),
        &bindings,
        push_size as u32,
        &[scene.gpu.features | features],
    )?;
    scene.trace.bind(&pipeline);
    Ok(pipeline)
}

/// Points a film kernel at a render's buffers.
pub fn bind_film(pipeline: &ComputePipeline, frame: &Buffer, film: &Buffer, aovs: Option<&Buffer>) {
    pipeline.bind_buffer(BINDING_FRAME, vk::DescriptorType::UNIFORM_BUFFER, frame);
    pipeline.bind_buffer(BINDING_FILM, vk::DescriptorType::STORAGE_BUFFER, film);
    if let Some(a) = aovs {
        pipeline.bind_buffer(BINDING_AOVS, vk::DescriptorType::STORAGE_BUFFER, a);
    }
}

/// Dispatches a film kernel over the pixels of `pass.tile`.
pub fn dispatch_tile(pipeline: &ComputePipeline, cmd: vk::CommandBuffer, pass: &PassConstants) {
    pipeline.dispatch(cmd, bytemuck::bytes_of(pass), tile_groups(pass.tile));
}

/// The workgroups of a film kernel over the pixels of `tile` (x0, y0, width, height).
pub fn tile_groups(tile: [u32; 4]) -> [u32; 3] {
    [
        tile[2].div_ceil(WORKGROUP_X),
        tile[3].div_ceil(WORKGROUP_Y),
        1,
    ]
}
