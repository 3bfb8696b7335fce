//! The one driver behind every render: the blocking render ([`super::Renderer::render`]) and
//! recorded sessions (src/render/session.rs) set up through the same stages here — the
//! integrator's kernels, the frame constants, the device film, the warm-up dispatch — and split
//! each dispatch into the same tiles, so that embedding and the command line cannot drift.

use super::film_kernel::tile_row_step;
use super::{Integrator, IntegratorPasses, PreparedScene, RenderSettings, Schedule};
use crate::error::{Error, Result};
use crate::film::{self, AOV_CHANNELS, Window};
use crate::layout::*;
use crate::scene::Camera;
use crate::trace::TraceMode;
use crate::vk::{Buffer, Context, MemoryLocation};
use ash::vk;
use std::sync::Arc;
use std::time::Instant;

/// Tiles of at most this many pixels a side: one dispatch each.
pub const TILE: u32 = 512;

/// The wall time a submission is sized to once the driver has measured the device's rate: long
/// enough that a submission's fixed costs (recording, submitting, waiting on its fence: about
/// 1 ms each on a GPU behind a sandbox, docs/performance-gpu.md) stay small, short enough that a
/// cancel, a time budget or a frame of the view is answered within it, and far below any
/// driver watchdog.
pub const SUBMIT_SECONDS: f64 = 0.05;

/// Fails when the render asks for another trace path than the scene was prepared for.
pub fn check_trace(prepared: &PreparedScene, mode: TraceMode) -> Result<()> {
    let wanted = match mode {
        TraceMode::Auto => return Ok(()),
        TraceMode::RayQuery => "rayquery",
        TraceMode::Bvh => "bvh",
    };
    if wanted != prepared.trace.name() {
        return Err(Error::Invalid(format!(
            "the scene was prepared for the {} trace path, the render asks for {wanted}",
            prepared.trace.name()
        )));
    }
    Ok(())
}

/// Fails, naming the figures, when the film of a render of `window` (for `seeds` seeds) would
/// need more host memory than the settings' limit or, without one, than the machine has
/// available.
pub fn check_memory(
    settings: &RenderSettings,
    window: Window,
    planes: usize,
    seeds: usize,
) -> Result<()> {
    use crate::film::memory;
    let evaluate = settings.evaluate_passes || settings.reference.is_some();
    let job = settings.samples.is_some_and(|r| r != (0, settings.spp));
    let per_pixel = memory::bytes_per_pixel(planes, evaluate, job);
    let pixels = window.pixels() as u64;
    // Each seed's output keeps its sums and planes.
    let need = memory::film_bytes(pixels, planes, evaluate, job).saturating_add(
        (seeds.max(1) as u64 - 1).saturating_mul(pixels * (16 * film::channels(planes) as u64)),
    );
    let (limit, what) = match settings.memory_limit {
        Some(l) => (l, "the memory limit (--memory-limit)"),
        None => match memory::available_bytes() {
            Some(a) => (
                a,
                "the memory available (MemAvailable, or the control group's or the address-space limit)",
            ),
            None => return Ok(()),
        },
    };
    if need.saturating_add(memory::PROCESS_BYTES) > limit {
        return Err(Error::Invalid(format!(
            "a {}x{} film needs about {} of host memory ({per_pixel} B a pixel: exact sums, \
             a block read back, resolved planes) besides {} for the driver and kernels, more \
             than {what}, {}; a render of a fixed sample count is split into bands of rows \
             where a band of 16 fits beside the frame's planes, but one with a time budget, a reference, a per-pass report, several \
             seeds or a sample range is rendered whole: render it in parts (--part, --crop) or \
             at a lower resolution",
            window.width(),
            window.height(),
            memory::format_bytes(need),
            memory::format_bytes(memory::PROCESS_BYTES),
            memory::format_bytes(limit)
        )));
    }
    Ok(())
}

/// An integrator with its kernels, configured for one render.
pub struct Setup {
    pub integrator: Arc<dyn Integrator>,
    pub kernels: Box<dyn IntegratorPasses>,
    /// The frame constants: scene, camera, integrator and the settings' clamp and test hooks.
    pub frame: Frame,
    pub aov_planes: &'static [&'static str],
    /// The pixels the device film covers (Frame.film_x0, film_y0, film_width).
    pub film_window: Window,
    /// Which pixels split their samples into the half-buffers (Frame.witness).
    pub split: film::Split,
}

impl Setup {
    /// Takes the kernels a prepared scene kept for the settings' integrator (else creates them)
    /// and writes the frame constants of a render through `camera` into a device film that
    /// covers `film_window`.
    pub fn new(
        ctx: &Context,
        prepared: &PreparedScene,
        camera: &Camera,
        settings: &RenderSettings,
        schedule: Schedule,
        film_window: Window,
    ) -> Result<Setup> {
        let integrator = settings.integrator.clone();
        let aov_planes = integrator.aov_planes();
        film::check_aov_names(aov_planes)
            .map_err(|e| Error::Invalid(format!("integrator {}: {e}", integrator.name())))?;
        let kernels = match prepared.take_kernels(integrator.name(), integrator.features()) {
            Some(k) => k,
            None => integrator.kernels(ctx, prepared)?,
        };
        let mut setup = Setup {
            integrator,
            kernels,
            frame: Frame::default(),
            aov_planes,
            film_window,
            split: film::Split::ALL,
        };
        setup.configure(ctx, prepared, camera, settings, schedule)?;
        Ok(setup)
    }

    /// Writes the frame constants again (after a scene update, say).
    pub fn configure(
        &mut self,
        ctx: &Context,
        prepared: &PreparedScene,
        camera: &Camera,
        settings: &RenderSettings,
        schedule: Schedule,
    ) -> Result<()> {
        let gpu = &prepared.gpu;
        let mut f = gpu.frame;
        crate::gpu_scene::set_camera(&mut f, camera, gpu.origin);
        self.integrator.configure(&mut f);
        if let Some(a) = &settings.allocation {
            a.counts.apply(&mut f);
        }
        f.clamp_luminance = settings.clamp.unwrap_or(0.0);
        f.nan_every = settings.inject_non_finite;
        let w = self.film_window;
        (f.film_x0, f.film_y0, f.film_width) = (w.x0, w.y0, w.width());
        // Witness blocks in a blocking render of fixed counts; a host's passes (a session) and
        // adaptive sampling (its counts set per pixel from the half-buffers) split every pixel.
        self.split = if schedule == Schedule::Fixed {
            film::Split::ALL
        } else {
            let adaptive = settings.adaptive.is_some();
            film::Split::of_render(camera.width, camera.height, settings.seed, adaptive)
        };
        f.witness = self.split.word();
        self.kernels
            .configure(ctx, prepared, &mut f, &*self.integrator, schedule)?;
        self.frame = f;
        Ok(())
    }

    /// Gives the kernels back to the prepared scene for later renders.
    pub fn keep(self, prepared: &PreparedScene) {
        let i = &self.integrator;
        prepared.keep_kernels(i.name(), i.features(), self.kernels);
    }

    /// One empty dispatch: drivers may compile the pipeline at its first dispatch (llvmpipe
    /// does: up to a second for `direct`, tens for `full`), which would otherwise be charged to
    /// the first pass. Returns its wall time.
    pub fn warm_up(&self, ctx: &Context) -> Result<f64> {
        let (warm, warm_cpu) = (Instant::now(), crate::vk::process_cpu_seconds());
        // One pixel of the film's window, no samples: the kernels reach the film by address,
        // with no robust bounds to drop an access outside it.
        let f = &self.frame;
        ctx.one_shot(|cmd| {
            self.kernels.record(
                cmd,
                &PassConstants {
                    tile: [f.film_x0, f.film_y0, 1, 1],
                    ..Default::default()
                },
            )
        })?;
        let seconds = warm.elapsed().as_secs_f64();
        ctx.notify_kernel(crate::vk::KernelEvent::Compiled(self.integrator.name()));
        if crate::vk::kernel_times() {
            crate::note!(
                "illum: warm-up dispatch of {}: {seconds:.3} s ({:.3} s of process CPU)",
                self.integrator.name(),
                crate::vk::process_cpu_seconds() - warm_cpu
            );
        }
        Ok(seconds)
    }
}

/// The device film of a render: FilmPixel sums, and the integrator's AOV planes (pixels x planes
/// vec4 sums, [pixel][plane]) when it has any.
pub struct FilmBuffers {
    pub film: Buffer,
    pub aovs: Option<Buffer>,
    pub planes: usize,
    /// The image pixels it covers.
    pub window: Window,
    /// The host buffer block reads land in (made at the first).
    readback: std::sync::Mutex<Option<Buffer>>,
}

impl FilmBuffers {
    /// Buffers for the pixels of `window` and `planes` AOV planes; `label` names them for
    /// messages.
    pub fn new(
        ctx: &Context,
        label: &str,
        window: Window,
        planes: usize,
        usage: vk::BufferUsageFlags,
    ) -> Result<FilmBuffers> {
        let pixels = window.pixels() as u64;
        let usage = usage | vk::BufferUsageFlags::STORAGE_BUFFER;
        let film = ctx.create_buffer(
            label,
            pixels * std::mem::size_of::<FilmPixel>() as u64,
            usage,
            MemoryLocation::GpuOnly,
        )?;
        let aovs = match planes {
            0 => None,
            p => Some(ctx.create_buffer(
                &format!("{label} aovs"),
                pixels * p as u64 * (AOV_CHANNELS * 4) as u64,
                usage,
                MemoryLocation::GpuOnly,
            )?),
        };
        Ok(FilmBuffers {
            film,
            aovs,
            planes,
            window,
            readback: Default::default(),
        })
    }

    pub fn device(&self) -> film::DeviceFilm<'_> {
        film::DeviceFilm {
            film: &self.film,
            aovs: self.aovs.as_ref(),
            aov_planes: self.planes,
            window: self.window,
            readback: Some(&self.readback),
        }
    }
}

/// The push constants of each tile of `window` for samples [first, first + count) with `seed`,
/// in the order they are dispatched; `interleave` (see [`super::film_kernel::interleaves_rows`]): each dispatch takes
/// its rows in an interleaved order. Either way every pixel's samples are the same.
pub fn tiles(
    window: Window,
    first: u32,
    count: u32,
    seed: u64,
    interleave: bool,
) -> Vec<PassConstants> {
    let mut out = Vec::new();
    for y0 in (window.y0..window.y1).step_by(TILE as usize) {
        for x0 in (window.x0..window.x1).step_by(TILE as usize) {
            let tile = [x0, y0, TILE.min(window.x1 - x0), TILE.min(window.y1 - y0)];
            out.push(PassConstants {
                first_sample: first,
                sample_count: count,
                seed_lo: seed as u32,
                seed_hi: (seed >> 32) as u32,
                tile,
                row_step: tile_row_step(interleave, tile),
                ..Default::default()
            });
        }
    }
    out
}

/// The push constants of the dispatches that take the first `count` entries of Frame.pixel_order
/// for samples [first, first + samples) with `seed`: grids of PACKED_WIDTH columns, at most
/// TILE x TILE pixels each, as the tiles are, their rows interleaved as theirs.
pub fn packed(
    count: u32,
    first: u32,
    samples: u32,
    seed: u64,
    interleave: bool,
) -> Vec<PassConstants> {
    const PACKED_WIDTH: u32 = 256;
    let most = TILE * TILE;
    (0..count)
        .step_by(most as usize)
        .map(|offset| {
            let n = most.min(count - offset);
            let tile = [offset, n, PACKED_WIDTH, n.div_ceil(PACKED_WIDTH)];
            PassConstants {
                first_sample: first,
                sample_count: samples,
                seed_lo: seed as u32,
                seed_hi: (seed >> 32) as u32,
                tile,
                order: 1,
                row_step: tile_row_step(interleave, tile),
                ..Default::default()
            }
        })
        .collect()
}
