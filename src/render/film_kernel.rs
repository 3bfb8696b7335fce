//! What every integrator's film kernel shares: its pipeline over film pixels (frame constants,
//! film, AOV planes, trace structure), its binding to a render's buffers and its dispatch over a
//! tile.

use super::PreparedScene;
use crate::error::Result;
use crate::layout::*;
use crate::vk::{Buffer, ComputePipeline, Context};
use ash::vk;

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
