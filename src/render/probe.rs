//! Host side of glsl/render/loop_probe.comp: whether the driver caps loop iterations. Older llvmpipe
//! (Mesa 22.3) ends every loop nest of an invocation after 65535 iterations in total, silently: a
//! dispatch of 8192 samples per pixel of a simple scene lost 8% of its samples, one of 32768 lost
//! 52%. Where the cap exists, the renderer runs one sample per invocation and dispatch.

use crate::error::Result;
use crate::shaders;
use crate::vk::{ComputePipeline, Context};
use ash::vk;

/// Iterations the probe asks for: more than 65535, in a nest of two loops.
const OUTER: u32 = 2;
const INNER: u32 = 40_000;

/// Runs the probe: true when the driver stopped the loops early.
pub fn loop_limited(ctx: &Context) -> Result<bool> {
    let data = ctx.upload(
        "loop probe",
        &[1u32, 1, 0],
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
    )?;
    let pipeline = ComputePipeline::new(
        ctx,
        "loop probe",
        shaders::LOOP_PROBE_PLAIN,
        &[(0, vk::DescriptorType::STORAGE_BUFFER)],
        8,
        &[],
    )?;
    pipeline.bind_buffer(0, vk::DescriptorType::STORAGE_BUFFER, &data);
    ctx.one_shot(|cmd| pipeline.dispatch(cmd, bytemuck::bytes_of(&[OUTER, INNER]), [1, 1, 1]))?;
    let out: Vec<u32> = ctx.download(&data, 3)?;
    Ok(out[2] != OUTER * INNER)
}
