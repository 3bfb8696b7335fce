//! The renderer: uploads a scene, builds its trace structure, runs the kernels in bounded
//! dispatches and resolves the film. It knows nothing of the command line; `main.rs` and
//! embedding applications call [`Renderer::render`].

mod primary;
mod upload;

pub use upload::GpuScene;

use crate::error::{Error, Result};
use crate::layout::*;
use crate::output::Film;
use crate::scene::Scene;
use crate::trace::{TraceMode, TraceStructure};
use crate::trace::rayquery::BuildStats;
use crate::vk::{Context, MemoryLocation};
use ash::vk;
use primary::PrimaryKernel;
use std::time::Instant;

#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub spp: u32,
    pub seed: u64,
    pub trace: TraceMode,
    /// Upper bound on camera samples (pixels × samples) in one submission, so that no dispatch
    /// runs long enough to trip a desktop driver's watchdog.
    pub samples_per_submit: u64,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            spp: 16,
            seed: 0,
            trace: TraceMode::Auto,
            samples_per_submit: 1 << 20,
        }
    }
}

#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    pub upload_seconds: f64,
    pub build: BuildStats,
    pub render_seconds: f64,
    pub total_seconds: f64,
    /// Camera samples whose beauty was NaN or infinite (counted, then replaced by 0).
    pub non_finite_samples: u64,
    pub trace: &'static str,
}

pub struct RenderOutput {
    pub film: Film,
    pub stats: RenderStats,
}

pub struct Renderer {
    ctx: Context,
}

impl Renderer {
    pub fn new(ctx: Context) -> Renderer {
        Renderer { ctx }
    }

    pub fn context(&self) -> &Context {
        &self.ctx
    }

    /// Renders `scene` at its camera's resolution. `progress(done, total)` is called after every
    /// submission with the number of samples per pixel completed.
    pub fn render(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        progress: &mut dyn FnMut(u32, u32),
    ) -> Result<RenderOutput> {
        let ctx = &self.ctx;
        let t0 = Instant::now();
        if settings.spp == 0 {
            return Err(Error::Invalid(
                "samples per pixel must be at least 1".into(),
            ));
        }
        let mode = settings.trace.resolve(ctx)?;
        let gpu = GpuScene::new(ctx, scene, mode == TraceMode::RayQuery)?;
        let upload_seconds = t0.elapsed().as_secs_f64();
        let trace = TraceStructure::build(ctx, &gpu, mode)?;
        let build = trace.build_stats().clone();

        let (w, h) = (scene.camera.width, scene.camera.height);
        let pixels = u64::from(w) * u64::from(h);
        let frame = ctx.upload(
            "frame",
            std::slice::from_ref(&gpu.frame),
            vk::BufferUsageFlags::UNIFORM_BUFFER,
        )?;
        let film_bytes = pixels * std::mem::size_of::<FilmPixel>() as u64;
        let film = ctx.create_buffer(
            "film",
            film_bytes,
            vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
        )?;
        ctx.one_shot(|cmd| {
            // SAFETY: the film buffer is alive until the wait.
            unsafe {
                ctx.device
                    .cmd_fill_buffer(cmd, film.buffer, 0, vk::WHOLE_SIZE, 0)
            }
        })?;
        let kernel = PrimaryKernel::new(ctx, &gpu, &trace, &frame, &film)?;

        // Tiles of at most 512x512 pixels; as many samples per dispatch as the budget allows.
        let t1 = Instant::now();
        const TILE: u32 = 512;
        let tile_pixels = u64::from(w.min(TILE)) * u64::from(h.min(TILE));
        let per_dispatch =
            (settings.samples_per_submit / tile_pixels).clamp(1, u64::from(settings.spp)) as u32;
        let mut done = 0;
        while done < settings.spp {
            let n = per_dispatch.min(settings.spp - done);
            for y0 in (0..h).step_by(TILE as usize) {
                for x0 in (0..w).step_by(TILE as usize) {
                    let pass = PassConstants {
                        first_sample: done,
                        sample_count: n,
                        seed_lo: settings.seed as u32,
                        seed_hi: (settings.seed >> 32) as u32,
                        tile: [x0, y0, TILE.min(w - x0), TILE.min(h - y0)],
                    };
                    ctx.one_shot(|cmd| kernel.record(cmd, &pass))?;
                }
            }
            done += n;
            progress(done, settings.spp);
        }
        let render_seconds = t1.elapsed().as_secs_f64();
        let raw: Vec<FilmPixel> = ctx.download(&film, pixels as usize)?;
        let (film, non_finite) = resolve(&raw, w, h, settings.spp);
        Ok(RenderOutput {
            film,
            stats: RenderStats {
                upload_seconds,
                build,
                render_seconds,
                total_seconds: t0.elapsed().as_secs_f64(),
                non_finite_samples: non_finite,
                trace: trace.name(),
            },
        })
    }
}

/// Sums per pixel → means, AOVs and the variance of the beauty mean.
fn resolve(raw: &[FilmPixel], w: u32, h: u32, spp: u32) -> (Film, u64) {
    let mut film = Film::new(w, h);
    let n = f64::from(spp);
    let mut variance = vec![[0.0f32; 3]; raw.len()];
    let mut non_finite = 0u64;
    for (i, p) in raw.iter().enumerate() {
        for c in 0..3 {
            let mean = f64::from(p.beauty[c]) / n;
            film.beauty[i][c] = mean as f32;
            film.albedo[i][c] = (f64::from(p.albedo[c]) / n) as f32;
            film.normal[i][c] = (f64::from(p.normal[c]) / n) as f32;
            film.emission[i][c] = (f64::from(p.emission[c]) / n) as f32;
            if spp > 1 {
                let m2 = f64::from(p.beauty_sq[c]) / n;
                let sample_var = (m2 - mean * mean).max(0.0) * n / (n - 1.0);
                variance[i][c] = (sample_var / n) as f32;
            }
        }
        let hits = p.albedo[3];
        film.depth[i] = if hits > 0.0 {
            p.normal[3] / hits
        } else {
            f32::INFINITY
        };
        non_finite += p.emission[3] as u64;
    }
    film.variance = Some(variance);
    (film, non_finite)
}
