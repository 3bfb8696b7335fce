//! Progressive rendering recorded into the host's own command buffers: a
//! [`RenderSession`] on a prepared scene records each pass (frame constants, dispatches, barriers)
//! into a command buffer the host owns and submits, and writes the beauty into the host's storage
//! image, and each AOV plane the host asks for ([`RenderSession::add_aov_target`]) into another.
//! The blocking [`Renderer::render`] stays for hosts that want nothing of this.
//!
//! # Synchronisation contract
//!
//! - A target is a 2D `VkImage` of format `R32G32B32A32_SFLOAT` with `STORAGE` usage, its
//!   extent the camera's resolution, one mip level and layer, and a view of it; the host owns
//!   both. [`TargetImage::before`] is the state (layout, stages, accesses) the host's earlier
//!   commands leave it in; each pass transitions it from there to `GENERAL` for its compute
//!   writes, and then to [`TargetImage::after`], the state the host's later commands expect
//!   (e.g. `TRANSFER_SRC_OPTIMAL` for a copy, `SHADER_READ_ONLY_OPTIMAL` for sampling). The
//!   previous contents are discarded (every pixel is written), so `before.layout` may be
//!   `UNDEFINED`. AOV targets follow the same contract, each with its own states.
//! - A pass first records a global memory barrier from `COMPUTE_SHADER | TRANSFER` writes to
//!   `COMPUTE_SHADER | TRANSFER` reads and writes: this orders it after the session's earlier
//!   passes in the same queue, whatever command buffers they were recorded in. Its own work is
//!   transfers (film clear, frame constants) and compute dispatches, on the session's own buffers
//!   and descriptor sets.
//! - The host records passes in the order it submits them, on the queue family of illum's
//!   context, and keeps the session (and the prepared scene) alive until every command buffer
//!   holding a pass has completed. Creating a session, [`RenderSession::update_scene`],
//!   [`RenderSession::refresh_cache`], [`RenderSession::add_aov_target`] and dropping the
//!   session must wait for the host's pending passes (a fence or `vkQueueWaitIdle`): they may
//!   submit blocking work of illum's own on its queue.
//!
//! # What the images hold
//!
//! The beauty: RGB the mean of the samples so far, alpha 1; each AOV image likewise for its plane
//! (the integrator's [`super::integrator::Integrator::aov_planes`], e.g. Direct,
//! IndirectDiffuse and Reflection for `full` and `path`). The film's sums stay on the device in
//! float32, where the blocking render moves each 256-sample block into exact host sums: up to 256
//! samples per pixel a pass gives the blocking render's images bit for bit wherever the device's
//! division is correctly rounded (lavapipe; tests/embed.rs), beyond that the two differ in
//! rounding.
//!
//! # The radiosity cache (`full`)
//!
//! The blocking render builds the cache on the host from the device's update records: warm-up
//! generations before the first sample, then a generation at samples 1, 2, 4, … The host's
//! command buffers cannot hand records back mid-frame, so a session keeps the cache fixed during
//! its passes: it runs the warm-up on illum's own queue, blocking, when it is created, after each
//! [`RenderSession::update_scene`] that changed a table or an instance transform, and on
//! [`RenderSession::refresh_cache`]; its images equal the blocking render's with
//! `integrator.radiosity_refresh` off (same seed, same samples; the session ignores the setting).
//! The cache is world-space, so a camera move keeps it; but its update paths start at the
//! camera's pixels (and its shape follows the image size), so after a move it still covers what
//! the old view saw: cells the new view reaches and the old did not are empty, and bounces there
//! continue in place (time, not bias: radiosity.rs). A host that moved far calls `refresh_cache`
//! (between frames) to warm it for the new view, after which the images equal the blocking
//! render's through the new camera again.

use super::driver::{FilmBuffers, Setup, tiles};
use super::film_kernel::interleaves_rows;
use super::{PreparedScene, RenderSettings, Renderer, SceneUpdate, Schedule};
use crate::error::{Error, Result};
use crate::film::{FILM_BLOCK, Window};
use crate::layout::*;
use crate::scene::{Camera, Scene};
use crate::vk::{Buffer, ComputePipeline, Context, ImageState, image_barrier};
use ash::vk;
use std::time::Instant;

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
    /// The integrator's kernels and the frame constants; None only while dropping.
    setup: Option<Setup>,
    resolve: ComputePipeline,
    frame: Buffer,
    film: FilmBuffers,
    /// The host's AOV images: plane index, target, its resolve pipeline (descriptor set).
    aov_targets: Vec<(u32, TargetImage, ComputePipeline)>,
    camera: Camera,
    target: TargetImage,
    /// Wall time of the last cache warm-up (0 without a cache).
    warmup_seconds: f64,
    /// Samples per dispatch: 1 on drivers that cut long loops short (see `probe`).
    per_dispatch: u32,
    /// Samples per pixel in the film after the last recorded pass.
    samples: u32,
}

impl Renderer {
    /// A session rendering `prepared` through `camera` into `target`, with the integrator, seed
    /// and clamp of `settings` (its sample counts are the passes'). With the `full` integrator
    /// this warms the radiosity cache up first, blocking (see the module doc).
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
        let full = crate::film::Window::full(camera.width, camera.height);
        let setup = Setup::new(&ctx, prepared, camera, settings, Schedule::Fixed, full)?;
        let frame = ctx.upload(
            "session frame",
            std::slice::from_ref(&Frame::default()),
            vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
        )?;
        let film = FilmBuffers::new(
            &ctx,
            "session film",
            full,
            setup.aov_planes.len(),
            vk::BufferUsageFlags::TRANSFER_DST,
        )?;
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
        resolve.bind_buffer(BINDING_FILM, vk::DescriptorType::STORAGE_BUFFER, &film.film);
        resolve.bind_storage_image(BINDING_IMAGE, target.view);
        let per_dispatch = if self.loop_limited()? { 1 } else { FILM_BLOCK };
        let mut s = RenderSession {
            ctx,
            prepared,
            settings: settings.clone(),
            setup: Some(setup),
            resolve,
            frame,
            film,
            aov_targets: Vec::new(),
            camera: camera.clone(),
            target,
            warmup_seconds: 0.0,
            per_dispatch,
            samples: 0,
        };
        s.refresh()?;
        // Drivers that compile a pipeline at its first dispatch do it now, not in the host's
        // first frame (the first pass clears the film).
        s.setup().warm_up(&s.ctx)?;
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
    /// Writes the frame constants of the camera, scene and settings (as `render_prepared`
    /// does), binds the kernels to the session's buffers and warms the integrator's cache up
    /// (blocking, on illum's queue): the host's passes must have completed.
    fn refresh(&mut self) -> Result<()> {
        let setup = self
            .setup
            .as_mut()
            .expect("the setup lives as long as the session");
        setup.configure(
            &self.ctx,
            self.prepared,
            &self.camera,
            &self.settings,
            Schedule::Fixed,
        )?;
        let film = &self.film;
        setup
            .kernels
            .bind(&self.frame, &film.film, film.aovs.as_ref());
        self.warmup_seconds = 0.0;
        if !setup.kernels.stateful() {
            return Ok(()); // no state to warm up
        }
        let warm = Instant::now();
        // The warm-up's update pass reads the frame constants from the buffer.
        let (frame, data) = (self.frame.buffer, setup.frame);
        self.ctx.one_shot(|cmd| {
            // SAFETY: the frame buffer is the session's; one_shot waits for the command buffer.
            unsafe {
                self.ctx
                    .device
                    .cmd_update_buffer(cmd, frame, 0, bytemuck::bytes_of(&data));
                barrier(&self.ctx.device, cmd);
            }
        })?;
        // Samples [0, 1): brings the state to what every pass reads.
        setup.kernels.begin(&self.ctx, self.settings.seed, 0, 1)?;
        self.warmup_seconds = warm.elapsed().as_secs_f64();
        Ok(())
    }

    fn setup(&self) -> &Setup {
        self.setup
            .as_ref()
            .expect("the setup lives as long as the session")
    }

    /// Moves the camera for the passes recorded from now on (same resolution); the next pass
    /// should start afresh (first_sample 0). Nothing is uploaded here: each pass writes the
    /// frame constants into its command buffer. A radiosity cache stays as it was warmed (see
    /// the module doc).
    pub fn set_camera(&mut self, camera: &Camera) -> Result<()> {
        check_extent(camera, &self.target)?;
        self.camera = camera.clone();
        let origin = self.prepared.gpu.origin;
        let setup = self
            .setup
            .as_mut()
            .expect("the setup lives as long as the session");
        crate::gpu_scene::set_camera(&mut setup.frame, &self.camera, origin);
        Ok(())
    }

    /// Updates the prepared scene (see [`PreparedScene::update`]) for the passes recorded from
    /// now on, and warms the radiosity cache up again if a table or transform changed. The
    /// host's pending passes must have completed.
    pub fn update_scene(&mut self, scene: &Scene) -> Result<SceneUpdate> {
        let u = self.prepared.update(&self.ctx, scene)?;
        if !u.tables.is_empty() || u.instances_moved {
            self.refresh()?;
        }
        Ok(u)
    }

    /// Warms the radiosity cache up again for the current camera (blocking; nothing to do
    /// without a cache). The host's pending passes must have completed.
    pub fn refresh_cache(&mut self) -> Result<()> {
        self.refresh()
    }

    /// Wall time of the last cache warm-up in seconds (0 without a cache).
    pub fn warmup_seconds(&self) -> f64 {
        self.warmup_seconds
    }

    /// The AOV planes the session's integrator writes (empty for `direct`).
    pub fn aov_planes(&self) -> &'static [&'static str] {
        self.setup().aov_planes
    }

    /// From the next pass on, also resolves AOV plane `plane` into the host's `target` (same
    /// contract as the beauty's). The host's pending passes must have completed.
    pub fn add_aov_target(&mut self, plane: &str, target: TargetImage) -> Result<()> {
        let (name, planes) = (self.setup().integrator.name(), self.setup().aov_planes);
        let index = planes.iter().position(|p| *p == plane).ok_or_else(|| {
            Error::Invalid(format!(
                "AOV plane {plane:?}: the {} integrator writes {}",
                name,
                if planes.is_empty() {
                    "none".to_string()
                } else {
                    planes.join(", ")
                }
            ))
        })? as u32;
        if self.aov_targets.iter().any(|t| t.0 == index) {
            return Err(Error::Invalid(format!(
                "AOV plane {plane:?} already has a target"
            )));
        }
        check_extent(&self.camera, &target)
            .map_err(|e| Error::Invalid(format!("AOV plane {plane:?}: {e}")))?;
        let aovs = self
            .film
            .aovs
            .as_ref()
            .expect("an integrator with planes has the buffer");
        let resolve = ComputePipeline::new(
            &self.ctx,
            "resolve_aov",
            crate::shaders::RESOLVE_AOV_PLAIN,
            &[
                (BINDING_AOVS, vk::DescriptorType::STORAGE_BUFFER),
                (BINDING_IMAGE, vk::DescriptorType::STORAGE_IMAGE),
            ],
            32,
            &[],
        )?;
        resolve.bind_buffer(BINDING_AOVS, vk::DescriptorType::STORAGE_BUFFER, aovs);
        resolve.bind_storage_image(BINDING_IMAGE, target.view);
        self.aov_targets.push((index, target, resolve));
        Ok(())
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
        let setup = self.setup();
        let kernels = &setup.kernels;
        let (w, h) = (self.camera.width, self.camera.height);
        // SAFETY: the caller guarantees a recording command buffer; every buffer and pipeline
        // recorded here belongs to the session, which outlives the command buffer's execution.
        unsafe {
            barrier(dev, cmd);
            if restart {
                dev.cmd_fill_buffer(cmd, self.film.film.buffer, 0, vk::WHOLE_SIZE, 0);
                if let Some(a) = &self.film.aovs {
                    dev.cmd_fill_buffer(cmd, a.buffer, 0, vk::WHOLE_SIZE, 0);
                }
            }
            dev.cmd_update_buffer(cmd, self.frame.buffer, 0, bytemuck::bytes_of(&setup.frame));
            barrier(dev, cmd);
            let mut s = pass.first_sample;
            while s < end {
                let n = self.per_dispatch.min(end - s);
                for pc in tiles(
                    Window::full(w, h),
                    s,
                    n,
                    self.settings.seed,
                    interleaves_rows(&self.ctx),
                ) {
                    kernels.record(cmd, &pc);
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
            let planes = setup.aov_planes.len() as u32;
            for (plane, t, resolve) in &self.aov_targets {
                image_barrier(dev, cmd, t.image, &t.before, &GENERAL_WRITE);
                resolve.dispatch(
                    cmd,
                    bytemuck::bytes_of(&[w, h, end, 0u32, *plane, planes, 0, 0]),
                    [w.div_ceil(WORKGROUP_X), h.div_ceil(WORKGROUP_Y), 1],
                );
                image_barrier(dev, cmd, t.image, &GENERAL_WRITE, &t.after);
            }
        }
        self.samples = end;
        Ok(())
    }
}

impl Drop for RenderSession<'_> {
    fn drop(&mut self) {
        if let Some(setup) = self.setup.take() {
            setup.keep(self.prepared);
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
