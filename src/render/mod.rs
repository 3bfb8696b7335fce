//! The renderer: uploads a scene, builds its trace structure, runs the kernels in progressive
//! passes of bounded dispatches, and resolves the film. It knows nothing of the command line;
//! `main.rs` and embedding applications call [`Renderer::render`].
//!
//! Every render can report its error against run time: after each pass the film is read back and
//! compared with a reference (RMSE, relMSE, MAE) or, without one, its relMSE is estimated from the
//! even and odd half-buffers (see [`crate::metrics`]).

pub mod adaptive;
pub mod allocation;
mod bands;
mod blocking;
mod driver;
pub mod film_kernel;
mod integrator;
mod params;
mod prepared;
mod probe;
mod profile;
mod progressive;
mod run;
mod session;
mod settings;

use crate::film::{self, FilmSums};
pub use crate::gpu_scene::SceneUpdate;
pub use crate::vk::ImageState;
pub use bands::Bands;
pub use integrator::{Integrator, IntegratorPasses, Schedule};
pub use params::Params;
pub use prepared::PreparedScene;
pub use progressive::{Peek, Progressive};
pub use session::{Pass, RenderSession, TargetImage};
pub use settings::RenderSettings;

use crate::error::Result;
use crate::metrics::ErrorMetrics;
use crate::scene::Scene;
use crate::trace::BuildStats;
use crate::vk::Context;
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
    /// Of `render_seconds`, the wall time spent moving complete film blocks off the device and
    /// adding them up exactly.
    pub commit_seconds: f64,
    /// Submissions of passes to the queue (each one recorded, submitted and waited for).
    pub submissions: u64,
    pub total_seconds: f64,
    pub spp: u32,
    /// Camera samples of the image, over all its pixels (with adaptive sampling fewer than
    /// pixels x spp; its pilot's are not counted, its time is in `render_seconds`).
    pub camera_samples: u64,
    /// Of `camera_samples`, those the witness blocks took beyond the render's spp (film::Split:
    /// their pixels take both sequences' samples).
    pub witness_samples: u64,
    /// Which pixels split their samples into the half-buffers (what a job's part records).
    pub split: crate::film::Split,
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
    /// How the frame was split into bands when its whole film would not fit the host memory
    /// (src/render/bands.rs); None: rendered whole.
    pub bands: Option<Bands>,
}

impl RenderStats {
    /// The figures of one seed's render (set-up and total times are the caller's).
    fn of(
        prepared: &PreparedScene,
        setup: &driver::Setup,
        o: &blocking::SeedOutput,
    ) -> RenderStats {
        let r = &o.resolved;
        RenderStats {
            upload_seconds: prepared.upload_seconds,
            build: prepared.build.clone(),
            render_seconds: o.wall,
            device_seconds: o.device,
            commit_seconds: o.commit,
            submissions: o.submissions,
            spp: o.done,
            camera_samples: r.counts.iter().map(|&c| u64::from(c)).sum(),
            split: setup.split,
            witness_samples: if setup.split.witnesses() {
                r.counts
                    .iter()
                    .zip(&r.split)
                    .filter(|(_, s)| **s)
                    .map(|(&c, _)| u64::from(c / 2))
                    .sum()
            } else {
                0
            },
            non_finite_samples: r.non_finite_samples,
            rays: r.rays,
            trace: prepared.trace.name(),
            integrator: setup.kernels.report(),
            dark_lights: prepared.gpu.dark_lights.clone(),
            emitters: prepared.gpu.emitters,
            clamped_samples: r.clamped_samples,
            interrupted: o.interrupted,
            ..Default::default()
        }
    }
}

pub struct RenderOutput {
    pub film: crate::film::Film,
    pub stats: RenderStats,
    /// One entry per pass when passes were evaluated; else only the last.
    pub passes: Vec<PassReport>,
    /// The exact sums behind the film: what a split render's jobs merge. None for a frame
    /// rendered in bands, whose sums were never held at once.
    pub job: Option<JobSums>,
}

impl RenderOutput {
    /// The exact sums behind the film, or why there are none.
    pub fn sums(&self) -> Result<&JobSums> {
        self.job.as_ref().ok_or_else(|| {
            crate::error::Error::Invalid(
                "the frame was rendered in bands (its film did not fit the memory): it has no \
                 sums to write; render a job with a sample range or crop"
                    .into(),
            )
        })
    }
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
        // The allocation pilot, once for all seeds and bands; its time counts as rendering.
        let (decided, pilot_seconds) = self.decide_allocation(prepared, camera, settings)?;
        let settings = &decided;
        if let Some(plan) = bands::plan(settings, camera, seeds.len()) {
            let out = self.render_bands(prepared, camera, settings, plan, progress, t0)?;
            return Ok(vec![out]);
        }
        let run = run::Run::new(self, prepared, camera, settings, seeds.len())?;
        let setup_seconds = t0.elapsed().as_secs_f64();
        let blocking = run.blocking(ctx, settings);
        blocking.head_start.set(pilot_seconds);
        let (first, last) = blocking.blocks();
        progress(0, last - first);
        let mut outputs = Vec::with_capacity(seeds.len());
        for (index, &seed) in seeds.iter().enumerate() {
            let t0 = if index == 0 { t0 } else { Instant::now() };
            if index > 0 {
                film::clear(ctx, run.film.device())?;
            }
            let o = blocking.render_seed(seed, progress)?;
            let interrupted = o.interrupted;
            // Later seeds reuse the set-up: only the film is cleared.
            let setup_seconds = if index == 0 { setup_seconds } else { 0.0 };
            outputs.push(run.output(prepared, settings, o, setup_seconds, t0));
            if interrupted {
                break;
            }
        }
        run.keep(prepared);
        Ok(outputs)
    }
}
