//! What a render sets up once for all its seeds (src/render/blocking.rs runs them): the
//! integrator's kernels and frame constants, the device film, the timer, adaptive sampling's
//! buffers.

use super::blocking::{Blocking, SeedOutput};
use super::driver::{FilmBuffers, Setup, TILE, check_memory, check_trace};
use super::{PreparedScene, RenderSettings, Schedule};
use crate::error::{Error, Result};
use crate::film::{self, FILM_BLOCK, Window};
use crate::scene::Camera;
use crate::vk::{Buffer, Context};
use ash::vk;
use std::time::Instant;

/// What a blocking render sets up once for all its seeds: the integrator's kernels and frame
/// constants, the device film, the timer and adaptive sampling's buffers.
pub struct Run {
    pub setup: Setup,
    frame: Buffer,
    pub film: FilmBuffers,
    timer: Option<crate::vk::GpuTimer>,
    /// With adaptive sampling: Frame.pixel_ends, Frame.pixel_order and the pilot's window.
    adaptive: Option<(Buffer, Buffer, Window)>,
    /// Time by kernel region, in builds whose kernels measure it (src/render/profile.rs).
    profile: Option<super::profile::Profile>,
    pub warmup_seconds: f64,
    per_dispatch: u32,
    loop_limited: bool,
    range: (u32, u32),
    window: Window,
    width: u32,
    height: u32,
}

impl Run {
    /// Sets up a render of `prepared` through `camera` with `settings` (checked here, with the
    /// host memory the films of `seeds` seeds need).
    pub fn new(
        renderer: &super::Renderer,
        prepared: &PreparedScene,
        camera: &Camera,
        settings: &RenderSettings,
        seeds: usize,
    ) -> Result<Run> {
        let ctx = renderer.context();
        let (w, h) = (camera.width, camera.height);
        settings.check(w, h)?;
        let (range, window) = settings.job(w, h)?;
        check_trace(prepared, settings.trace)?;
        check_memory(
            settings,
            window,
            settings.integrator.aov_planes().len(),
            seeds,
        )?;
        // The device film covers the job's pixels; with adaptive sampling its pilot's, which
        // contain them.
        let pilot = settings
            .adaptive
            .map(|a| super::adaptive::pilot_window(&a, window, w, h));
        let film_window = pilot.unwrap_or(window);
        let mut setup = Setup::new(
            ctx,
            prepared,
            camera,
            settings,
            Schedule::Progressive,
            film_window,
        )?;
        // Adaptive sampling: each pixel's end sample (all of them until the counts are
        // decided) and the order in which the dispatches take the pixels.
        let adaptive = match settings.adaptive {
            Some(_) => {
                let all = vec![u32::MAX; w as usize * h as usize];
                let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
                let ends = ctx.upload("pixel ends", &all, usage)?;
                let order = ctx.upload("pixel order", &all, usage)?;
                setup.frame.pixel_ends = ends.address;
                setup.frame.pixel_order = order.address;
                Some((ends, order, film_window))
            }
            None => None,
        };
        let profile = super::profile::Profile::new(ctx, film_window.pixels())?;
        if let Some(p) = &profile {
            setup.frame.profile = p.address();
        }
        let frame = ctx.upload(
            "frame",
            std::slice::from_ref(&setup.frame),
            vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
        )?;
        let film = FilmBuffers::new(
            ctx,
            "film",
            film_window,
            setup.aov_planes.len(),
            vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::TRANSFER_SRC,
        )?;
        film::clear(ctx, film.device())?;
        setup.kernels.bind(&frame, &film.film, film.aovs.as_ref());
        let timer = crate::vk::GpuTimer::new(ctx)?;
        let warmup_seconds = setup.warm_up(ctx)?;
        // As many samples per dispatch as the budget allows over a tile, never across a film
        // block (src/film/mod.rs): blocks leave the device whole.
        let tile_pixels =
            u64::from(window.width().min(TILE)) * u64::from(window.height().min(TILE));
        let loop_limited = renderer.loop_limited()?;
        let per_dispatch = if loop_limited {
            1
        } else {
            (settings.samples_per_submit / tile_pixels).clamp(1, u64::from(FILM_BLOCK)) as u32
        };
        Ok(Run {
            setup,
            frame,
            film,
            timer,
            adaptive,
            profile,
            warmup_seconds,
            per_dispatch,
            loop_limited,
            range,
            window,
            width: w,
            height: h,
        })
    }

    /// The blocking render over the run's set-up.
    pub fn blocking<'a>(&'a self, ctx: &'a Context, settings: &'a RenderSettings) -> Blocking<'a> {
        Blocking {
            ctx,
            settings,
            setup: &self.setup,
            film: &self.film,
            timer: self.timer.as_ref(),
            width: self.width,
            range: self.range,
            window: self.window,
            per_dispatch: self.per_dispatch,
            loop_limited: self.loop_limited,
            adaptive: self.adaptive.as_ref().map(|(e, o, pilot)| (e, o, *pilot)),
            profile: self.profile.as_ref(),
            height: self.height,
            head_start: std::cell::Cell::new(0.0),
            whole: false,
        }
    }

    /// Points the run at `camera` (the same resolution) and clears the film: the next seed's
    /// render starts afresh through it.
    pub fn set_camera(
        &mut self,
        ctx: &Context,
        prepared: &PreparedScene,
        camera: &Camera,
        settings: &RenderSettings,
    ) -> Result<()> {
        if (camera.width, camera.height) != (self.width, self.height) {
            return Err(Error::Invalid(format!(
                "the camera renders {}x{}, the run was set up for {}x{}",
                camera.width, camera.height, self.width, self.height
            )));
        }
        // What the run owns, not the scene or the settings: kept across the new frame.
        let frame = &self.setup.frame;
        let (ends, order, profile) = (frame.pixel_ends, frame.pixel_order, frame.profile);
        self.setup
            .configure(ctx, prepared, camera, settings, Schedule::Progressive)?;
        let frame = &mut self.setup.frame;
        (frame.pixel_ends, frame.pixel_order, frame.profile) = (ends, order, profile);
        ctx.write(&self.frame, 0, std::slice::from_ref(&self.setup.frame))?;
        if let Some(p) = &self.profile {
            p.clear(ctx)?;
        }
        film::clear(ctx, self.film.device())
    }

    /// One seed's render as the blocking render returns it.
    pub fn output(
        &self,
        prepared: &PreparedScene,
        settings: &RenderSettings,
        o: SeedOutput,
        setup_seconds: f64,
        t0: Instant,
    ) -> super::RenderOutput {
        let mut stats = super::RenderStats::of(prepared, &self.setup, &o);
        stats.warmup_seconds = self.warmup_seconds;
        stats.setup_seconds = setup_seconds;
        stats.total_seconds = t0.elapsed().as_secs_f64();
        if let Some(a) = &settings.allocation {
            stats.integrator.push((
                "allocation".into(),
                format!("{} ({})", a.counts.describe(), a.how),
            ));
        }
        super::RenderOutput {
            stats,
            film: o.resolved.film,
            passes: o.passes,
            job: Some(super::JobSums {
                range: o.range,
                total_spp: settings.spp,
                sums: o.sums,
            }),
        }
    }

    /// Gives the kernels back to the prepared scene for later renders.
    pub fn keep(self, prepared: &PreparedScene) {
        self.setup.keep(prepared);
    }
}
