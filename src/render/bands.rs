//! A frame whose film would not fit the host memory, rendered in horizontal bands in turn. Each
//! band is a crop of the frame, so its pixels are those the whole frame would have (a pixel's
//! samples do not depend on the window: the crops of a split render merge bit for bit into the
//! whole), and only one band's exact sums, device film and read-back are held at a time; the
//! frame keeps its resolved planes (src/film/memory.rs, `frame_bytes_per_pixel`).
//!
//! Only a render with a fixed sample count can be split so: a time budget, a reference or a
//! per-pass report measures the whole frame between passes, and a job of a split render writes
//! sums. Those are refused, as before, when the whole frame does not fit.

use super::adaptive::Target;
use super::{PassReport, PreparedScene, RenderOutput, RenderSettings, RenderStats, Renderer};
use crate::error::Result;
use crate::film::{self, Film, Window, memory};
use crate::scene::Camera;
use std::time::Instant;

/// Rows of a band are a multiple of this (the radiosity cache's and the tiles' blocks divide it).
const BAND_ROWS: u32 = 16;

/// A band's film takes at most this much memory, however much the budget leaves: larger bands
/// are no faster (a 4096^2 frame of the default scene rendered in 61.2 s in 64 bands and 61.6 s
/// whole), and a render need not take all of a machine's memory (docs/outputs.md, "Memory").
const BAND_BYTES: u64 = 1 << 30;

/// How a frame was split into bands (RenderStats::bands).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bands {
    /// Rows of each band (the last may have fewer).
    pub rows: u32,
    /// Bands of the frame.
    pub count: u32,
    /// Bands rendered: `count`, or fewer where the render was cancelled (the rows beyond are
    /// empty, with SampleCount 0; RenderStats::spp is of the bands rendered).
    pub done: u32,
    /// The memory budget the bands were sized for, in bytes.
    pub budget: u64,
}

impl Bands {
    /// Rows rendered (all of them unless the render was cancelled) of a frame `height` tall.
    pub fn rows_done(&self, height: u32) -> u32 {
        (self.done * self.rows).min(height)
    }
}

/// The rows of each band when `settings`' render of `camera`'s frame needs bands: its whole film
/// would not fit the memory budget, a band would, and the render can be split (a fixed sample
/// count, one seed, no reference, report, sample range or crop, no adaptive mean). None where the
/// frame renders whole (the render's own memory check then refuses what does not fit).
pub fn plan(settings: &RenderSettings, camera: &Camera, seeds: usize) -> Option<(u32, u64)> {
    let (w, h) = (camera.width, camera.height);
    let splittable = seeds == 1
        && settings.time.is_none()
        && settings.reference.is_none()
        && !settings.evaluate_passes
        && settings.samples.is_none()
        && settings.crop.is_none()
        && !matches!(settings.adaptive.map(|a| a.target), Some(Target::Mean(_)));
    if !splittable || h <= BAND_ROWS {
        return None;
    }
    let planes = settings.integrator.aov_planes().len();
    let limit = settings.memory_limit.or_else(memory::available_bytes)?;
    let per_pixel = memory::bytes_per_pixel(planes, false, false);
    let whole = memory::film_bytes(u64::from(w) * u64::from(h), planes, false, false);
    if whole.saturating_add(memory::PROCESS_BYTES) <= limit {
        return None;
    }
    let frame = u64::from(w) * u64::from(h) * memory::frame_bytes_per_pixel(planes);
    let left = limit.checked_sub(memory::PROCESS_BYTES + frame)?;
    // A band's film holds its rows and, with adaptive sampling, the pilot's ring around them.
    let ring = if settings.adaptive.is_some() { 2 } else { 0 };
    let left = left.min(BAND_BYTES);
    let rows = (left / (per_pixel * u64::from(w))).checked_sub(ring)?;
    let rows = (rows.min(u64::from(h)) as u32) / BAND_ROWS * BAND_ROWS;
    (rows > 0 && rows < h).then_some((rows, limit))
}

impl Renderer {
    /// Renders `camera`'s frame of `prepared` in bands of `rows` rows, each as the crop of the
    /// frame it is, pasting each band's resolved planes into the frame's.
    pub(super) fn render_bands(
        &self,
        prepared: &PreparedScene,
        camera: &Camera,
        settings: &RenderSettings,
        (rows, budget): (u32, u64),
        progress: &mut dyn FnMut(u32, u32),
        t0: Instant,
    ) -> Result<RenderOutput> {
        let (w, h) = (camera.width, camera.height);
        let count = h.div_ceil(rows);
        let planes: Vec<String> = settings
            .integrator
            .aov_planes()
            .iter()
            .map(|p| p.to_string())
            .collect();
        let mut frame = Frame::new(w, h, &planes);
        let mut stats = RenderStats::default();
        let mut last = PassReport::default();
        let mut relmse = (0.0, 0u64);
        let mut done = 0;
        for k in 0..count {
            let band = Window {
                x0: 0,
                y0: k * rows,
                x1: w,
                y1: ((k + 1) * rows).min(h),
            };
            let cancelled = settings
                .cancel
                .as_ref()
                .is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed));
            if k > 0 && cancelled {
                stats.interrupted = true;
                break;
            }
            let mut s = settings.clone();
            s.crop = Some(band);
            // The band was sized for this budget, the frame's planes counted: measured again, the
            // memory available would already be short of them.
            s.memory_limit = Some(budget);
            let start = if k == 0 { t0 } else { Instant::now() };
            let mut step = |d: u32, b: u32| {
                let all = u64::from(k) * u64::from(b) + u64::from(d);
                progress((all / u64::from(count)) as u32, b);
            };
            let mut out =
                self.render_prepared_from(prepared, camera, &s, &[s.seed], &mut step, start)?;
            let o = out.pop().expect("one render per seed");
            frame.paste(&o.film, band, o.stats.spp);
            let b = &o.stats;
            if k == 0 {
                stats = b.clone();
            } else {
                stats.setup_seconds += b.setup_seconds;
                stats.warmup_seconds += b.warmup_seconds;
                stats.render_seconds += b.render_seconds;
                stats.device_seconds += b.device_seconds;
                stats.commit_seconds += b.commit_seconds;
                stats.submissions += b.submissions;
                stats.camera_samples += b.camera_samples;
                stats.witness_samples += b.witness_samples;
                stats.non_finite_samples += b.non_finite_samples;
                stats.clamped_samples += b.clamped_samples;
                stats.rays += b.rays;
                stats.spp = stats.spp.min(b.spp);
                stats.integrator = b.integrator.clone();
            }
            if let Some(p) = o.passes.last() {
                last.pass = last.pass.max(p.pass);
                last.device_seconds += p.device_seconds;
                last.wall_seconds += p.wall_seconds;
                last.non_finite_samples += p.non_finite_samples;
                if let Some(e) = p.estimated_relmse {
                    let n = band.pixels() as u64;
                    relmse = (relmse.0 + e * n as f64, relmse.1 + n);
                }
            }
            done = k + 1;
            if b.interrupted {
                stats.interrupted = true;
                break;
            }
        }
        last.spp = stats.spp;
        // The frame's estimate is the mean over its pixels, as each band's is over its own.
        last.estimated_relmse = (relmse.1 > 0).then(|| relmse.0 / relmse.1 as f64);
        stats.total_seconds = t0.elapsed().as_secs_f64();
        stats.bands = Some(Bands {
            rows,
            count,
            done,
            budget,
        });
        Ok(RenderOutput {
            film: frame.finish(),
            stats,
            passes: vec![last],
            job: None,
        })
    }
}

/// The frame's planes as the bands fill them.
struct Frame {
    film: Film,
    variance: Vec<[f32; 3]>,
    has_variance: bool,
    /// Each pixel's samples (0 until its band is rendered).
    samples: Vec<f32>,
}

impl Frame {
    fn new(width: u32, height: u32, planes: &[String]) -> Frame {
        let mut film = Film::new(width, height);
        let n = film.pixel_count();
        film.aovs = planes
            .iter()
            .map(|name| film::AovPlane {
                name: name.clone(),
                rgb: vec![[0.0; 3]; n],
            })
            .collect();
        Frame {
            film,
            variance: vec![[0.0; 3]; n],
            has_variance: false,
            samples: vec![0.0; n],
        }
    }

    /// Copies band `window`'s planes (full rows) into the frame; `spp` is the count of its
    /// pixels where the band has no SampleCount plane (they all took the same).
    fn paste(&mut self, band: &Film, window: Window, spp: u32) {
        let f = &mut self.film;
        let at = window.y0 as usize * f.width as usize;
        let r = at..at + band.pixel_count();
        f.beauty[r.clone()].copy_from_slice(&band.beauty);
        f.albedo[r.clone()].copy_from_slice(&band.albedo);
        f.normal[r.clone()].copy_from_slice(&band.normal);
        f.depth[r.clone()].copy_from_slice(&band.depth);
        f.emission[r.clone()].copy_from_slice(&band.emission);
        for (plane, b) in f.aovs.iter_mut().zip(&band.aovs) {
            plane.rgb[r.clone()].copy_from_slice(&b.rgb);
        }
        if let Some(v) = &band.variance {
            self.variance[r.clone()].copy_from_slice(v);
            self.has_variance = true;
        }
        match &band.samples {
            Some(s) => self.samples[r].copy_from_slice(s),
            None => self.samples[r].fill(spp as f32),
        }
    }

    /// The frame's film, with its SampleCount plane where the pixels' counts differ (adaptive
    /// sampling, or bands a cancel left out), as a whole frame's would have.
    fn finish(mut self) -> Film {
        if self.has_variance {
            self.film.variance = Some(self.variance);
        }
        let most = self.samples.iter().copied().fold(0.0, f32::max);
        if self.samples.iter().any(|&s| s != most) {
            self.film.samples = Some(self.samples);
        }
        self.film
    }
}
