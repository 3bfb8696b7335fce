//! Progressive rendering recorded into the host's own command buffers (issue 14): a
//! [`RenderSession`] on a prepared scene records each pass (frame constants, dispatches, barriers)
//! into a command buffer the host owns and submits, and writes the beauty into the host's storage
//! image. The blocking [`Renderer::render`] stays for hosts that want nothing of this.
//!
//! # Synchronisation contract
//!
//! - The target is a 2D `VkImage` of format `R32G32B32A32_SFLOAT` with `STORAGE` usage, its
//!   extent the camera's resolution, one mip level and layer, and a view of it; the host owns
//!   both. [`TargetImage::before`] is the state (layout, stages, accesses) the host's earlier
//!   commands leave it in; each pass transitions it from there to `GENERAL` for its compute
//!   writes, and then to [`TargetImage::after`], the state the host's later commands expect
//!   (e.g. `TRANSFER_SRC_OPTIMAL` for a copy, `SHADER_READ_ONLY_OPTIMAL` for sampling). The
//!   previous contents are discarded (every pixel is written), so `before.layout` may be
//!   `UNDEFINED`.
//! - A pass first records a global memory barrier from `COMPUTE_SHADER | TRANSFER` writes to
//!   `COMPUTE_SHADER | TRANSFER` reads and writes: this orders it after the session's earlier
//!   passes in the same queue, whatever command buffers they were recorded in. Its own work is
//!   transfers (film clear, frame constants) and compute dispatches, on the session's own buffers
//!   and descriptor sets.
//! - The host records passes in the order it submits them, on the queue family of illum's
//!   context, and keeps the session (and the prepared scene) alive until every command buffer
//!   holding a pass has completed. Scene updates ([`RenderSession::update_scene`]) and dropping the
//!   session must wait for the host's pending passes (a fence or `vkQueueWaitIdle`).
//!
//! # What the image holds
//!
//! The beauty only (no AOV images yet), RGB the mean of the samples so far, alpha 1. The film's
//! sums stay on the device in float32, where the blocking render moves each 256-sample block into
//! exact host sums: up to 256 samples per pixel a pass gives the blocking render's image bit for
//! bit wherever the device's division is correctly rounded (lavapipe; tests/embed.rs), beyond
//! that the two differ in rounding.

use super::film::FILM_BLOCK;
use super::integrator::{self, IntegratorPasses};
use super::{PreparedScene, RenderSettings, Renderer, SceneUpdate};
use crate::error::{Error, Result};
use crate::layout::*;
use crate::scene::{Camera, Scene};
use crate::vk::{Buffer, ComputePipeline, Context, MemoryLocation};
use ash::vk;

/// Where an image is: its layout and the stages and accesses of the commands around.
#[derive(Clone, Copy, Debug)]
pub struct ImageState {
    pub layout: vk::ImageLayout,
    pub stage: vk::PipelineStageFlags,
    pub access: vk::AccessFlags,
}

/// The host's storage image a session writes into (see the module's contract).
#[derive(Clone, Copy, Debug)]
pub struct TargetImage {
    pub image: vk::Image,
    pub view: vk::ImageView,
    pub extent: [u32; 2],
    /// The state the host's earlier commands leave the image in.
    pub before: ImageState,
    /// The state a pass leaves it in, for the host's later commands.
    pub after: ImageState,
}

/// One progressive pass: samples [first_sample, first_sample + sample_count) of every pixel. A
/// pass with first_sample 0 starts the image afresh (after a camera move, say); otherwise it must
/// continue where the session's previous pass ended.
#[derive(Clone, Copy, Debug)]
pub struct Pass {
    pub first_sample: u32,
    pub sample_count: u32,
}

pub struct RenderSession<'p> {
    ctx: Context,
    prepared: &'p mut PreparedScene,
    settings: RenderSettings,
    integrator: &'static str,
    /// The settings' kernel feature bits (Integrator::features).
    features: u32,
    kernels: Option<Box<dyn IntegratorPasses>>,
    resolve: ComputePipeline,
    frame: Buffer,
    frame_data: Frame,
    film: Buffer,
    camera: Camera,
    target: TargetImage,
    /// Samples per dispatch: 1 on drivers that cut long loops short (see `probe`).
    per_dispatch: u32,
    /// Samples per pixel in the film after the last recorded pass.
    samples: u32,
}

impl Renderer {
    /// A session rendering `prepared` through `camera` into `target`, with the integrator, seed
    /// and clamp of `settings` (its sample counts are the passes').
    pub fn session<'p>(
        &self,
        prepared: &'p mut PreparedScene,
        camera: &Camera,
        settings: &RenderSettings,
        target: TargetImage,
    ) -> Result<RenderSession<'p>> {
        let ctx = self.context().clone();
        settings.check(camera.width, camera.height)?;
        check_extent(camera, &target)?;
        let pixels = u64::from(camera.width) * u64::from(camera.height);
        let frame = ctx.upload(
            "session frame",
            std::slice::from_ref(&Frame::default()),
            vk::BufferUsageFlags::UNIFORM_BUFFER,
        )?;
        let film = ctx.create_buffer(
            "session film",
            pixels * std::mem::size_of::<FilmPixel>() as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        let integrator = integrator::select(settings);
        if !integrator.aov_planes().is_empty() {
            // Their AOV planes and cache generations are not carried through sessions yet.
            return Err(Error::Invalid(format!(
                "a render session records the direct integrator only; {} renders through \
                 Renderer::render or render_prepared",
                integrator.name()
            )));
        }
        // The prepared scene's kernels if an earlier render left them, given back on drop.
        let kernels = match prepared.take_kernels(integrator.name(), integrator.features()) {
            Some(k) => k,
            None => integrator.kernels(&ctx, prepared)?,
        };
        kernels.bind(&frame, &film, None);
        let resolve = ComputePipeline::new(
            &ctx,
            "resolve_image",
            crate::shaders::RESOLVE_IMAGE_PLAIN,
            &[
                (BINDING_FILM, vk::DescriptorType::STORAGE_BUFFER),
                (BINDING_IMAGE, vk::DescriptorType::STORAGE_IMAGE),
            ],
            16,
            &[],
        )?;
        resolve.bind_buffer(BINDING_FILM, vk::DescriptorType::STORAGE_BUFFER, &film);
        resolve.bind_storage_image(BINDING_IMAGE, target.view);
        let per_dispatch = if self.loop_limited()? { 1 } else { FILM_BLOCK };
        let mut s = RenderSession {
            ctx,
            prepared,
            settings: settings.clone(),
            integrator: integrator.name(),
            features: integrator.features(),
            kernels: Some(kernels),
            resolve,
            frame,
            frame_data: Frame::default(),
            film,
            camera: camera.clone(),
            target,
            per_dispatch,
            samples: 0,
        };
        s.refresh_frame();
        Ok(s)
    }
}

fn check_extent(camera: &Camera, target: &TargetImage) -> Result<()> {
    if target.extent != [camera.width, camera.height] {
        return Err(Error::Invalid(format!(
            "the target image is {}x{}, the camera renders {}x{}",
            target.extent[0], target.extent[1], camera.width, camera.height
        )));
    }
    Ok(())
}

impl RenderSession<'_> {
    /// The frame constants of the camera, scene and settings (as `render_prepared` writes them).
    fn refresh_frame(&mut self) {
        let gpu = &self.prepared.gpu;
        let mut f = gpu.frame;
        crate::gpu_scene::set_camera(&mut f, &self.camera, gpu.origin);
        integrator::select(&self.settings).configure(&mut f);
        f.clamp_luminance = self.settings.clamp.unwrap_or(0.0);
        f.nan_every = self.settings.inject_non_finite;
        self.frame_data = f;
    }

    /// Moves the camera for the passes recorded from now on (same resolution); the next pass
    /// should start afresh (first_sample 0). Nothing is uploaded here: each pass writes the
    /// frame constants into its command buffer.
    pub fn set_camera(&mut self, camera: &Camera) -> Result<()> {
        check_extent(camera, &self.target)?;
        self.camera = camera.clone();
        self.refresh_frame();
        Ok(())
    }

    /// Updates the prepared scene (see [`PreparedScene::update`]) for the passes recorded from
    /// now on. The host's pending passes must have completed.
    pub fn update_scene(&mut self, scene: &Scene) -> Result<SceneUpdate> {
        let u = self.prepared.update(&self.ctx, scene)?;
        self.refresh_frame();
        Ok(u)
    }

    /// Samples per pixel in the image after the passes recorded so far.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Records `pass` into `cmd` (see the module's synchronisation contract).
    ///
    /// # Safety
    /// `cmd` must be a primary command buffer in the recording state, outside a render pass, of
    /// a pool of the context's queue family; the target's image and view must be valid when it
    /// executes, and the session alive until it has completed.
    pub unsafe fn record_pass(&mut self, cmd: vk::CommandBuffer, pass: &Pass) -> Result<()> {
        let restart = pass.first_sample == 0;
        if pass.sample_count == 0 || (!restart && pass.first_sample != self.samples) {
            return Err(Error::Invalid(format!(
                "pass of samples [{}, +{}): a pass takes at least one sample and starts at 0 or \
                 where the previous pass ended ({})",
                pass.first_sample, pass.sample_count, self.samples
            )));
        }
        let end = pass
            .first_sample
            .checked_add(pass.sample_count)
            .ok_or_else(|| Error::Invalid("pass sample range overflows".into()))?;
        let dev = &self.ctx.device;
        let kernels = self
            .kernels
            .as_ref()
            .expect("kernels live as long as the session");
        let (w, h) = (self.camera.width, self.camera.height);
        // SAFETY: the caller guarantees a recording command buffer; every buffer and pipeline
        // recorded here belongs to the session, which outlives the command buffer's execution.
        unsafe {
            barrier(dev, cmd);
            if restart {
                dev.cmd_fill_buffer(cmd, self.film.buffer, 0, vk::WHOLE_SIZE, 0);
            }
            dev.cmd_update_buffer(
                cmd,
                self.frame.buffer,
                0,
                bytemuck::bytes_of(&self.frame_data),
            );
            barrier(dev, cmd);
            const TILE: u32 = 512;
            let mut s = pass.first_sample;
            while s < end {
                let n = self.per_dispatch.min(end - s);
                for y0 in (0..h).step_by(TILE as usize) {
                    for x0 in (0..w).step_by(TILE as usize) {
                        let pc = PassConstants {
                            first_sample: s,
                            sample_count: n,
                            seed_lo: self.settings.seed as u32,
                            seed_hi: (self.settings.seed >> 32) as u32,
                            tile: [x0, y0, TILE.min(w - x0), TILE.min(h - y0)],
                        };
                        kernels.record(cmd, &pc);
                    }
                }
                barrier(dev, cmd);
                s += n;
            }
            let t = &self.target;
            image_barrier(dev, cmd, t.image, &t.before, &GENERAL_WRITE);
            self.resolve.dispatch(
                cmd,
                bytemuck::bytes_of(&[w, h, end, 0u32]),
                [w.div_ceil(WORKGROUP_X), h.div_ceil(WORKGROUP_Y), 1],
            );
            image_barrier(dev, cmd, t.image, &GENERAL_WRITE, &t.after);
        }
        self.samples = end;
        Ok(())
    }
}

impl Drop for RenderSession<'_> {
    fn drop(&mut self) {
        if let Some(k) = self.kernels.take() {
            self.prepared
                .keep_kernels(self.integrator, self.features, k);
        }
    }
}

/// The image as a pass writes it.
const GENERAL_WRITE: ImageState = ImageState {
    layout: vk::ImageLayout::GENERAL,
    stage: vk::PipelineStageFlags::COMPUTE_SHADER,
    access: vk::AccessFlags::SHADER_WRITE,
};

/// Orders the session's compute and transfer work before what follows (see the contract).
unsafe fn barrier(dev: &ash::Device, cmd: vk::CommandBuffer) {
    let stages = vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER;
    let mb = [vk::MemoryBarrier::default()
        .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
        .dst_access_mask(
            vk::AccessFlags::SHADER_READ
                | vk::AccessFlags::SHADER_WRITE
                | vk::AccessFlags::UNIFORM_READ
                | vk::AccessFlags::TRANSFER_WRITE,
        )];
    // SAFETY: cmd is recording (the caller's contract).
    unsafe {
        dev.cmd_pipeline_barrier(
            cmd,
            stages,
            stages,
            vk::DependencyFlags::empty(),
            &mb,
            &[],
            &[],
        )
    }
}

unsafe fn image_barrier(
    dev: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    from: &ImageState,
    to: &ImageState,
) {
    let or_top = |s: vk::PipelineStageFlags, fallback| if s.is_empty() { fallback } else { s };
    let b = [vk::ImageMemoryBarrier::default()
        .old_layout(from.layout)
        .new_layout(to.layout)
        .src_access_mask(from.access)
        .dst_access_mask(to.access)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(
            vk::ImageSubresourceRange::default()
                .aspect_mask(vk::ImageAspectFlags::COLOR)
                .level_count(1)
                .layer_count(1),
        )];
    // SAFETY: cmd is recording (the caller's contract).
    unsafe {
        dev.cmd_pipeline_barrier(
            cmd,
            or_top(from.stage, vk::PipelineStageFlags::TOP_OF_PIPE),
            or_top(to.stage, vk::PipelineStageFlags::BOTTOM_OF_PIPE),
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &b,
        )
    }
}
