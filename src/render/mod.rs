//! The renderer: uploads a scene, builds its trace structure, runs the kernels in progressive
//! passes of bounded dispatches, and resolves the film. It knows nothing of the command line;
//! `main.rs` and embedding applications call [`Renderer::render`].
//!
//! Every render can report its error against run time: after each pass the film is read back and
//! compared with a reference (RMSE, relMSE, MAE) or, without one, its relMSE is estimated from the
//! even and odd half-buffers (see [`crate::metrics`]).

mod direct;
mod indirect;
pub mod integrator;
mod prepared;
mod probe;
mod session;
mod settings;

use crate::film::{self, BoundaryBlock, FILM_BLOCK, FilmSums, Resolved};
pub use crate::gpu_scene::SceneUpdate;
pub use prepared::PreparedScene;
pub use session::{ImageState, Pass, RenderSession, TargetImage};
pub use settings::{
    ControlVariates, IntegratorKind, IntegratorSettings, LightSelection, RenderSettings, Technique,
};

use crate::error::{Error, Result};
use crate::layout::*;
use crate::metrics::{self, ErrorMetrics};
use crate::scene::Scene;
use crate::trace::BuildStats;
use crate::trace::TraceMode;
use crate::vk::{Context, GpuTimer, MemoryLocation};
use ash::vk;

use std::sync::atomic::Ordering;
use std::time::Instant;

/// One row of the error-against-time report. Times and samples are cumulative.
#[derive(Clone, Debug, Default)]
pub struct PassReport {
    pub pass: u32,
    pub spp: u32,
    /// Sum of the device time of the kernels (timestamp queries); wall time where the queue has
    /// no timestamps.
    pub device_seconds: f64,
    /// Wall-clock time of rendering so far (submission and waiting; evaluation excluded).
    pub wall_seconds: f64,
    /// Against the reference, when there is one.
    pub error: Option<ErrorMetrics>,
    /// From the half-buffers (needs at least 2 samples).
    pub estimated_relmse: Option<f64>,
    pub non_finite_samples: u64,
}

#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    pub upload_seconds: f64,
    /// The empty first dispatch (pipeline compilation by drivers that compile lazily).
    pub warmup_seconds: f64,
    pub build: BuildStats,
    /// Wall time from the start of `render` to the first pass: kernel compilation, upload,
    /// trace-structure build and warm-up.
    pub setup_seconds: f64,
    /// Wall time of the passes (steady-state rendering; evaluation excluded).
    pub render_seconds: f64,
    pub device_seconds: f64,
    pub total_seconds: f64,
    pub spp: u32,
    /// Camera samples whose beauty was NaN or infinite (counted, then replaced by 0).
    pub non_finite_samples: u64,
    /// Rays traced: camera rays and shadow rays.
    pub rays: u64,
    /// Lights of the scene that emit nothing (zero radiance or zero size), left out of the render.
    pub dark_lights: Vec<String>,
    /// Lights rendered, emissive shapes and triangles included (0: only emission seen directly).
    pub emitters: u32,
    /// Camera samples whose direct lighting the firefly clamp reduced (0 when it is off).
    pub clamped_samples: u64,
    pub trace: &'static str,
    /// The integrator's own figures (e.g. the radiosity cache's size and update time), as
    /// (name, value): written to the EXR header as illum.<name>.
    pub integrator: Vec<(String, String)>,
    /// The render stopped early through [`RenderSettings::cancel`]; `spp` says how far it got.
    pub interrupted: bool,
}

pub struct RenderOutput {
    pub film: crate::output::Film,
    pub stats: RenderStats,
    /// One entry per pass when passes were evaluated; else only the last.
    pub passes: Vec<PassReport>,
    /// The exact sums behind the film: what a split render's jobs merge.
    pub job: JobSums,
}

/// The exact film sums of a render or of one job of a split render (src/film/mod.rs).
#[derive(Clone, Debug, PartialEq)]
pub struct JobSums {
    /// Samples [A, B) of every pixel of the window that the sums own.
    pub range: (u32, u32),
    /// Samples per pixel of the whole image.
    pub total_spp: u32,
    pub sums: FilmSums,
}

pub struct Renderer {
    ctx: Context,
    /// Whether the driver caps loop iterations (see `probe`), found at the first render.
    loop_limited: std::sync::OnceLock<bool>,
}

impl Renderer {
    pub fn new(ctx: Context) -> Renderer {
        Renderer {
            ctx,
            loop_limited: std::sync::OnceLock::new(),
        }
    }

    /// Whether the driver ends loops early (older llvmpipe), so that each dispatch must take one
    /// sample per pixel.
    pub fn loop_limited(&self) -> Result<bool> {
        if let Some(&l) = self.loop_limited.get() {
            return Ok(l);
        }
        let l = probe::loop_limited(&self.ctx)?;
        Ok(*self.loop_limited.get_or_init(|| l))
    }

    pub fn context(&self) -> &Context {
        &self.ctx
    }

    /// Renders `scene` at its camera's resolution. `progress(spp_done, spp_budget)` is called
    /// once with 0 samples when set-up (kernel compilation, upload, build, warm-up) is over, then
    /// after every round of dispatches (with a time budget, spp_budget is the cap).
    pub fn render(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        progress: &mut dyn FnMut(u32, u32),
    ) -> Result<RenderOutput> {
        let mut out = self.render_seeds(scene, settings, &[settings.seed], progress)?;
        Ok(out.pop().expect("one render per seed"))
    }

    /// Renders `scene` once per seed in `seeds` (`settings.seed` is ignored), each exactly as
    /// [`Renderer::render`] would with that seed, but with one upload, trace structure and
    /// pipeline for all: independent renders for the price of their samples (the pipeline
    /// compilation dominates small renders on CPU drivers). Used by statistical tests.
    pub fn render_seeds(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        seeds: &[u64],
        progress: &mut dyn FnMut(u32, u32),
    ) -> Result<Vec<RenderOutput>> {
        let t0 = Instant::now();
        settings.check(scene.camera.width, scene.camera.height)?;
        let prepared = self.prepare(scene, settings.trace)?;
        self.render_prepared_from(&prepared, &scene.camera, settings, seeds, progress, t0)
    }

    /// Renders a prepared scene (see [`Renderer::prepare`]) through `camera` once per seed, as
    /// [`Renderer::render_seeds`] would: nothing of the scene is uploaded or built again, only the
    /// frame constants (camera, settings). The camera may move and change resolution; positions
    /// stay relative to the camera the scene was prepared with, so it should stay near it (within
    /// ~1e3 of the scene's size) to keep their precision.
    pub fn render_prepared(
        &self,
        prepared: &PreparedScene,
        camera: &crate::scene::Camera,
        settings: &RenderSettings,
        seeds: &[u64],
        progress: &mut dyn FnMut(u32, u32),
    ) -> Result<Vec<RenderOutput>> {
        self.render_prepared_from(prepared, camera, settings, seeds, progress, Instant::now())
    }

    fn render_prepared_from(
        &self,
        prepared: &PreparedScene,
        camera: &crate::scene::Camera,
        settings: &RenderSettings,
        seeds: &[u64],
        progress: &mut dyn FnMut(u32, u32),
        t0: Instant,
    ) -> Result<Vec<RenderOutput>> {
        let ctx = &self.ctx;
        let (w, h) = (camera.width, camera.height);
        settings.check(w, h)?;
        let (range, window) = settings.job(w, h)?;
        let pixels = u64::from(w) * u64::from(h);
        let wanted = match settings.trace {
            TraceMode::Auto => None,
            TraceMode::RayQuery => Some("rayquery"),
            TraceMode::Bvh => Some("bvh"),
        };
        if let Some(want) = wanted
            && want != prepared.trace.name()
        {
            return Err(Error::Invalid(format!(
                "the scene was prepared for the {} trace path, the render asks for {want}",
                prepared.trace.name()
            )));
        }
        let (gpu, trace) = (&prepared.gpu, &prepared.trace);
        let mut frame_constants = gpu.frame;
        crate::gpu_scene::set_camera(&mut frame_constants, camera, gpu.origin);
        let integrator = integrator::select(settings);
        let kernel = match prepared.take_kernels(integrator.name(), integrator.features()) {
            Some(k) => k,
            None => integrator.kernels(ctx, prepared)?,
        };
        integrator.configure(&mut frame_constants);
        frame_constants.clamp_luminance = settings.clamp.unwrap_or(0.0);
        frame_constants.nan_every = settings.inject_non_finite;
        kernel.configure(ctx, prepared, &mut frame_constants, settings)?;
        let upload_seconds = prepared.upload_seconds;
        let build = prepared.build.clone();

        let frame = ctx.upload(
            "frame",
            std::slice::from_ref(&frame_constants),
            vk::BufferUsageFlags::UNIFORM_BUFFER,
        )?;
        let film_usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::TRANSFER_SRC;
        let film_buffer = ctx.create_buffer(
            "film",
            pixels * std::mem::size_of::<FilmPixel>() as u64,
            film_usage,
            MemoryLocation::GpuOnly,
        )?;
        // The integrator's AOV planes: pixels x planes vec4 sums, [pixel][plane].
        let aov_planes: Vec<String> = integrator
            .aov_planes()
            .iter()
            .map(|p| p.to_string())
            .collect();
        film::check_aov_names(&aov_planes)
            .map_err(|e| Error::Invalid(format!("integrator {}: {e}", integrator.name())))?;
        let aov_buffer = match aov_planes.len() {
            0 => None,
            p => Some(ctx.create_buffer(
                "aovs",
                pixels * p as u64 * (film::AOV_CHANNELS * 4) as u64,
                film_usage,
                MemoryLocation::GpuOnly,
            )?),
        };
        let device_film = film::DeviceFilm {
            film: &film_buffer,
            aovs: aov_buffer.as_ref(),
            aov_planes: aov_planes.len(),
        };
        film::clear(ctx, device_film)?;
        kernel.bind(&frame, &film_buffer, aov_buffer.as_ref());
        let timer = GpuTimer::new(ctx)?;
        let evaluate = settings.evaluate_passes || settings.reference.is_some();

        // Warm-up: one empty dispatch, since drivers may compile the pipeline at its first
        // dispatch (llvmpipe does: up to a second for the integrator), which would otherwise be
        // charged to the first pass and skew the error-against-time curve.
        let (warm, warm_cpu) = (Instant::now(), crate::vk::process_cpu_seconds());
        ctx.one_shot(|cmd| {
            kernel.record(
                cmd,
                &PassConstants {
                    tile: [0, 0, 1, 1],
                    ..Default::default()
                },
            )
        })?;
        let warmup_seconds = warm.elapsed().as_secs_f64();
        if crate::vk::kernel_times() {
            eprintln!(
                "illum: warm-up dispatch of {}: {warmup_seconds:.3} s ({:.3} s of process CPU)",
                integrator.name(),
                crate::vk::process_cpu_seconds() - warm_cpu
            );
        }
        let setup_seconds = t0.elapsed().as_secs_f64();
        // The samples this job renders: its range widened to whole blocks.
        let first = film::block_of(range.0, settings.spp).0;
        let last = film::block_of(range.1 - 1, settings.spp).1;
        let budget = last - first;
        progress(0, budget);
        let cancelled = || {
            settings
                .cancel
                .as_ref()
                .is_some_and(|c| c.load(Ordering::Relaxed))
        };

        // Tiles of at most 512x512 pixels; as many samples per dispatch as the budget allows,
        // never across a film block (src/film/mod.rs): blocks leave the device whole.
        const TILE: u32 = 512;
        let tile_pixels =
            u64::from(window.width().min(TILE)) * u64::from(window.height().min(TILE));
        let per_dispatch = if self.loop_limited()? {
            1
        } else {
            (settings.samples_per_submit / tile_pixels).clamp(1, u64::from(FILM_BLOCK)) as u32
        };
        let mut outputs = Vec::with_capacity(seeds.len());
        for (index, &seed) in seeds.iter().enumerate() {
            let t0 = if index == 0 { t0 } else { Instant::now() };
            if index > 0 {
                film::clear(ctx, device_film)?;
            }
            let mut interrupted = false;
            let (mut done, mut wall, mut device) = (0u32, 0.0f64, 0.0f64);
            let mut sums = FilmSums::new(window, aov_planes.clone());
            let mut passes = Vec::new();
            let mut last_resolved = None;
            while done < budget && !interrupted {
                // Passes grow by half the samples so far (log-spaced points on the error curve);
                // under a time budget a pass is sized to the time left at the measured rate.
                let mut pass = (done / 2).max(1).min(budget - done);
                if let Some(t) = settings.time {
                    if wall >= t {
                        break;
                    }
                    if done > 0 {
                        let rate = f64::from(done) / wall.max(1e-9);
                        pass = pass.min(((t - wall) * rate).max(1.0) as u32);
                    }
                }
                let start = Instant::now();
                let mut k = 0;
                while k < pass {
                    let s = first + done + k;
                    let (block_start, block_end) = film::block_of(s, settings.spp);
                    let n = per_dispatch.min(pass - k).min(block_end - s);
                    // The integrator's own state (a cache generation) may end a dispatch early.
                    let n = kernel.begin(ctx, seed, s, n)?.clamp(1, n);
                    for y0 in (window.y0..window.y1).step_by(TILE as usize) {
                        for x0 in (window.x0..window.x1).step_by(TILE as usize) {
                            let pc = PassConstants {
                                first_sample: s,
                                sample_count: n,
                                seed_lo: seed as u32,
                                seed_hi: (seed >> 32) as u32,
                                tile: [x0, y0, TILE.min(window.x1 - x0), TILE.min(window.y1 - y0)],
                            };
                            ctx.one_shot(|cmd| {
                                GpuTimer::around(timer.as_ref(), cmd, || kernel.record(cmd, &pc))
                            })?;
                            if let Some(t) = &timer {
                                device += t.seconds()?;
                            }
                        }
                    }
                    k += n;
                    if s + n == block_end {
                        // The block is complete: exact sums if the job owns all of it, else kept
                        // whole as a boundary block.
                        let block = film::download_window(ctx, device_film, w, window)?;
                        if block_start >= range.0 && block_end <= range.1 {
                            sums.add_block(&block);
                        } else {
                            sums.boundary.push(BoundaryBlock {
                                start: block_start,
                                end: block_end,
                                sums: block,
                            });
                        }
                        film::clear(ctx, device_film)?;
                    }
                    progress(done + k, budget);
                    if cancelled() {
                        // Every pixel has done + k samples: stop here, keeping them.
                        interrupted = true;
                        break;
                    }
                }
                done += k;
                let elapsed = start.elapsed().as_secs_f64();
                wall += elapsed;
                if timer.is_none() {
                    device += elapsed;
                }
                let mut report = PassReport {
                    pass: passes.len() as u32,
                    spp: done,
                    device_seconds: device,
                    wall_seconds: wall,
                    ..Default::default()
                };
                if evaluate {
                    // Reads the unfinished block without moving it: the block grid stays fixed.
                    let mut peek = sums.all_sums();
                    if (first + done) % FILM_BLOCK != 0 && first + done != last {
                        let block = film::download_window(ctx, device_film, w, window)?;
                        film::add_block(peek.to_mut(), &block, sums.channels());
                    }
                    let r =
                        film::resolve(&peek, &aov_planes, window.width(), window.height(), done);
                    evaluate_pass(&mut report, &r, settings.reference.as_deref());
                    passes.push(report);
                    last_resolved = Some(r);
                } else {
                    passes.clear();
                    passes.push(report);
                }
            }
            if done < budget {
                // A time budget ended the render inside a block: keep what was rendered.
                let block = film::download_window(ctx, device_film, w, window)?;
                sums.add_block(&block);
            }
            let resolved = match last_resolved {
                Some(r) if r.spp == done => r,
                _ => film::resolve(
                    &sums.all_sums(),
                    &aov_planes,
                    window.width(),
                    window.height(),
                    done,
                ),
            };
            if !evaluate && let Some(p) = passes.last_mut() {
                evaluate_pass(p, &resolved, settings.reference.as_deref());
            }
            outputs.push(RenderOutput {
                stats: RenderStats {
                    upload_seconds,
                    warmup_seconds,
                    // Later seeds reuse the set-up: only the film is cleared.
                    setup_seconds: if index == 0 { setup_seconds } else { 0.0 },
                    build: build.clone(),
                    render_seconds: wall,
                    device_seconds: device,
                    total_seconds: t0.elapsed().as_secs_f64(),
                    spp: done,
                    non_finite_samples: resolved.non_finite_samples,
                    rays: resolved.rays,
                    trace: trace.name(),
                    integrator: kernel.report(),
                    dark_lights: gpu.dark_lights.clone(),
                    emitters: gpu.emitters,
                    clamped_samples: resolved.clamped_samples,
                    interrupted,
                },
                film: resolved.film,
                passes,
                job: JobSums {
                    range: (range.0, range.1.min(first + done)),
                    total_spp: settings.spp,
                    sums,
                },
            });
            if interrupted {
                break;
            }
        }
        prepared.keep_kernels(integrator.name(), integrator.features(), kernel);
        Ok(outputs)
    }
}

fn evaluate_pass(report: &mut PassReport, r: &Resolved, reference: Option<&[[f32; 3]]>) {
    report.non_finite_samples = r.non_finite_samples;
    report.estimated_relmse = metrics::estimated_relmse(&r.film.beauty, &r.even, &r.odd, r.spp);
    report.error = reference.map(|reference| metrics::compare(&r.film.beauty, reference));
}
