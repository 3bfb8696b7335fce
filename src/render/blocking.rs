//! The blocking render's run (src/render/run.rs), seed by seed: the allocation and adaptive
//! pilots, progressive passes of bounded submissions under a sample or time budget, film blocks
//! moved into exact host sums as they complete, and the per-pass error report. Its set-up (kernels,
//! frame constants, device film, tiles) is the driver's (src/render/driver.rs), shared with
//! sessions.

use super::RenderSettings;
use super::driver::{FilmBuffers, SUBMIT_SECONDS, Setup, packed, tiles};
use super::film_kernel::interleaves_rows;
use crate::error::Result;
use crate::film::{self, Window};
use crate::vk::{Buffer, Context};
use std::time::Instant;

/// A blocking render's run over its seeds: set up once, then each seed renders into the same
/// device film, its blocks moved into exact host sums as they complete (src/film/mod.rs).
pub struct Blocking<'a> {
    pub ctx: &'a Context,
    pub settings: &'a RenderSettings,
    pub setup: &'a Setup,
    pub film: &'a FilmBuffers,
    pub timer: Option<&'a crate::vk::GpuTimer>,
    /// The image's width (the device film's row length).
    pub width: u32,
    /// The job's sample range and pixel window.
    pub range: (u32, u32),
    pub window: Window,
    /// Samples per dispatch at most (1 where the driver cuts long loops short).
    pub per_dispatch: u32,
    /// Whether the driver cuts long loops short (then every dispatch takes one sample).
    pub loop_limited: bool,
    /// With adaptive sampling: each pixel's end sample (Frame.pixel_ends), the order in which
    /// dispatches take the pixels (Frame.pixel_order) and the pilot's pixels, the window and the
    /// ring around it (src/render/adaptive.rs).
    pub adaptive: Option<(&'a Buffer, &'a Buffer, Window)>,
    /// Time by kernel region (builds that measure it; src/render/profile.rs).
    pub profile: Option<&'a super::profile::Profile>,
    /// The image's height.
    pub height: u32,
    /// Wall seconds spent for the render before its first seed (the allocation pilot): the
    /// first seed's [`Blocking::start`] counts them as rendering, under its time budget too.
    pub head_start: std::cell::Cell<f64>,
    /// A render nobody watches (the allocation pilot's candidates): its samples in one pass,
    /// without the passes' submissions and waits, which were half a small candidate's time.
    pub whole: bool,
}

/// Where one seed's render stands: what [`Blocking::render_seed`] runs to the end, and what an
/// interactive host (src/render/progressive.rs) steps through a frame at a time.
pub struct Progress {
    seed: u64,
    /// The job's first sample (of its first block) and the samples it renders from there.
    first: u32,
    budget: u32,
    planes: Vec<String>,
    evaluate: bool,
    /// Samples done per pixel, from the first sample of the first block.
    done: u32,
    wall: f64,
    device: f64,
    /// Wall seconds spent moving complete blocks off the device and adding them up.
    commit: f64,
    /// Submissions so far, and the camera samples per wall second of the last one (0: none yet).
    submissions: u64,
    rate: f64,
    interrupted: bool,
    sums: film::FilmSums,
    passes: Vec<super::PassReport>,
    last_resolved: Option<film::Resolved>,
    /// With adaptive sampling, once the pixels' counts are decided: the sample at which every
    /// pixel of the window has stopped, and the window's end samples in descending order (as
    /// Frame.pixel_order has the pixels).
    stop: Option<u32>,
    ends: Vec<u32>,
}

impl Progress {
    /// Samples per pixel done.
    pub fn done(&self) -> u32 {
        self.done
    }

    /// Wall seconds of rendering so far.
    pub fn wall(&self) -> f64 {
        self.wall
    }

    /// The exact sums of the blocks that have left the device.
    pub fn sums(&self) -> &film::FilmSums {
        &self.sums
    }

    /// A copy to finish apart (a snapshot of the image so far), the render going on.
    fn snapshot(&self) -> Progress {
        Progress {
            planes: self.planes.clone(),
            sums: self.sums.clone(),
            passes: self.passes.clone(),
            last_resolved: None,
            ends: self.ends.clone(),
            ..*self
        }
    }
}

impl Blocking<'_> {
    /// The samples this job renders: its range widened to whole blocks.
    pub fn blocks(&self) -> (u32, u32) {
        let spp = self.settings.spp;
        (
            film::block_of(self.range.0, spp).0,
            film::block_of(self.range.1 - 1, spp).1,
        )
    }

    fn cancelled(&self) -> bool {
        self.settings
            .cancel
            .as_ref()
            .is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed))
    }

    /// Renders with `seed` (the film cleared), calling `progress(done, budget)` after every
    /// round of dispatches. Returns the sums, the pass reports, the resolved film, the wall and
    /// device seconds, and whether the render was cancelled.
    pub fn render_seed(&self, seed: u64, progress: &mut dyn FnMut(u32, u32)) -> Result<SeedOutput> {
        let mut p = self.start(seed)?;
        while !p.interrupted
            && let Some(pass) = self.plan_pass(&p)
        {
            self.pass(&mut p, pass, progress)?;
        }
        self.finish(p)
    }

    /// A seed's render before its first sample (the film cleared): with adaptive sampling, its
    /// pilot has run and the pixels' counts are decided.
    pub fn start(&self, seed: u64) -> Result<Progress> {
        let (first, last) = self.blocks();
        let planes: Vec<String> = self
            .setup
            .aov_planes
            .iter()
            .map(|p| p.to_string())
            .collect();
        let mut p = Progress {
            seed,
            first,
            budget: last - first,
            evaluate: self.settings.evaluate_passes || self.settings.reference.is_some(),
            done: 0,
            wall: self.head_start.take(),
            device: 0.0,
            commit: 0.0,
            submissions: 0,
            rate: 0.0,
            interrupted: false,
            sums: film::FilmSums::new(self.window, planes.clone()),
            planes,
            passes: Vec::new(),
            last_resolved: None,
            stop: None,
            ends: Vec::new(),
        };
        if let Some((ends, _, _)) = self.adaptive {
            // A fresh seed: every pixel renders until its count is decided.
            let pixels = self.width as usize * self.height as usize;
            self.ctx.write(ends, 0, &vec![u32::MAX; pixels])?;
            // The counts come from a pilot of samples of their own, left out of the image.
            let start = Instant::now();
            self.pilot(seed)?;
            self.decide_counts(&mut p, first)?;
            film::clear(self.ctx, self.film.device())?;
            p.wall += start.elapsed().as_secs_f64();
            p.device += start.elapsed().as_secs_f64();
        }
        Ok(p)
    }

    /// Renders the next `pass` samples (at most those left), moving complete blocks off the
    /// device, and reports the pass (evaluated when the settings ask).
    pub fn pass(
        &self,
        p: &mut Progress,
        pass: u32,
        progress: &mut dyn FnMut(u32, u32),
    ) -> Result<()> {
        let pass = pass.min(p.budget - p.done);
        if pass == 0 {
            return Ok(());
        }
        let start = Instant::now();
        let from = p.first + p.done;
        let k = self.render_pass(p, p.seed, from, pass, p.budget, progress)?;
        p.done += k;
        let elapsed = start.elapsed().as_secs_f64();
        p.wall += elapsed;
        if self.timer.is_none() {
            p.device += elapsed;
        }
        self.report_pass(p)
    }

    /// The render's output after the samples done: the block in progress joins the sums.
    pub fn finish(&self, mut p: Progress) -> Result<SeedOutput> {
        if let Some(profile) = self.profile {
            crate::note!("{}", profile.report(self.ctx)?);
        }
        let end = p.first + p.done;
        // Adaptive sampling stopped every pixel: none of the range is left undone.
        let stopped = p.stop.is_some_and(|s| end >= s) && !p.interrupted;
        if stopped {
            // Adaptive sampling stopped every pixel inside a block: the block is complete (no
            // pixel takes more of it), so it leaves as a whole one would.
            let (start, block_end) = film::block_of(end.max(1) - 1, self.settings.spp);
            if end > 0 && block_end != end {
                self.commit_block(&mut p, start, block_end)?;
            }
        } else if p.done < p.budget {
            // A time budget ended the render inside a block: keep what was rendered.
            let block = film::download_window(self.ctx, self.film.device(), self.window)?;
            p.sums.add_block(&block);
        }
        let resolved = match p.last_resolved.take() {
            Some(r) if r.spp == p.done => r,
            _ => film::resolve(
                &p.sums.all_sums(),
                &p.planes,
                (self.window.width(), self.window.height()),
                p.done,
                self.setup.split,
                (self.window.x0, self.window.y0),
            ),
        };
        if !p.evaluate
            && let Some(r) = p.passes.last_mut()
        {
            evaluate_pass(r, &resolved, self.settings.reference.as_deref());
        }
        let covered = if stopped {
            self.range.1
        } else {
            self.range.1.min(end)
        };
        Ok(SeedOutput {
            range: (self.range.0, covered),
            done: p.done,
            wall: p.wall,
            device: p.device,
            commit: p.commit,
            submissions: p.submissions,
            interrupted: p.interrupted,
            sums: p.sums,
            passes: p.passes,
            resolved,
        })
    }

    /// What [`Blocking::finish`] would give now, the render going on.
    pub fn snapshot(&self, p: &Progress) -> Result<SeedOutput> {
        self.finish(p.snapshot())
    }

    /// The float32 sums of the block in progress (None at a block's end, where the device film
    /// is empty): with [`Progress::sums`], what the image holds so far.
    pub fn block_in_progress(&self, p: &Progress) -> Result<Option<Vec<f32>>> {
        if (p.first + p.done) % film::FILM_BLOCK == 0 || p.done == p.budget {
            return Ok(None);
        }
        film::download_window(self.ctx, self.film.device(), self.window).map(Some)
    }

    /// The next pass's sample count: half the samples so far (log-spaced points on the error
    /// curve), under a time budget sized to the time left at the measured rate; None when the
    /// time is up or adaptive sampling has stopped every pixel.
    pub fn plan_pass(&self, p: &Progress) -> Option<u32> {
        let end = p
            .stop
            .map_or(p.budget, |s| s.saturating_sub(p.first).min(p.budget));
        if p.done >= end {
            return None;
        }
        let mut pass = if self.whole && self.settings.time.is_none() {
            end - p.done
        } else {
            (p.done / 2).max(1).min(end - p.done)
        };
        if let Some(t) = self.settings.time {
            if p.wall >= t {
                return None;
            }
            if p.done > 0 {
                let rate = f64::from(p.done) / p.wall.max(1e-9);
                pass = pass.min(((t - p.wall) * rate).max(1.0) as u32);
            }
        }
        Some(pass)
    }

    /// Renders the pilot of adaptive sampling into the (cleared) film: samples [0, min_spp) of
    /// the window and the ring of pixels around it, with a seed of their own
    /// ([`super::adaptive::pilot_seed`]): independent of the image's samples.
    fn pilot(&self, seed: u64) -> Result<()> {
        let (Some(t), Some((_, _, ring))) = (self.settings.adaptive, self.adaptive) else {
            return Ok(());
        };
        let seed = super::adaptive::pilot_seed(seed);
        let kernels = &self.setup.kernels;
        let mut s = 0;
        while s < t.min_spp {
            let n = self.per_dispatch.min(t.min_spp - s);
            let n = kernels.begin(self.ctx, seed, s, n)?.clamp(1, n);
            let dispatches = tiles(ring, s, n, seed, interleaves_rows(self.ctx));
            self.ctx.one_shot(|cmd| {
                for pc in &dispatches {
                    kernels.record(cmd, pc)
                }
            })?;
            s += n;
        }
        Ok(())
    }

    /// Decides every pixel's count from the pilot, which the device film holds, and uploads the
    /// pixels' end samples.
    fn decide_counts(&self, p: &mut Progress, first: u32) -> Result<()> {
        let planes = &p.planes;
        let (Some(t), Some((ends, order, ring))) = (self.settings.adaptive, self.adaptive) else {
            return Ok(());
        };
        let block = film::download_window(self.ctx, self.film.device(), ring)?;
        let channels = film::channels(planes.len());
        let mut sums = vec![0i128; block.len()];
        film::add_block(&mut sums, &block, channels);
        let r = film::resolve(
            &sums,
            planes,
            (ring.width(), ring.height()),
            t.min_spp,
            film::Split::ALL,
            (ring.x0, ring.y0),
        );
        // Each pixel's rays a sample: the cost of its samples.
        let rays = crate::layout::FilmPixel::BEAUTY_SQ + 3;
        let costs: Vec<f64> = sums
            .chunks_exact(channels)
            .map(|s| film::from_fixed(s[rays], rays) / f64::from(t.min_spp))
            .collect();
        let e = super::adaptive::pixel_ends(
            &t,
            &r,
            &costs,
            ring,
            self.window,
            (self.width, self.height),
            self.settings.spp,
        );
        let w = self.window;
        let mut pixels: Vec<u32> = (w.y0..w.y1)
            .flat_map(|y| (w.x0..w.x1).map(move |x| y * self.width + x))
            .collect();
        // Descending end, in buckets of ends within 2^(1/4) of each other, each in image order:
        // each pass takes a prefix (the buckets with a pixel still sampling), and neighbours
        // in the image stay neighbours in a dispatch (their rays and texels are alike).
        let bucket = |end: u32| (f64::from(end).log2() * 4.0).floor() as i64;
        pixels.sort_by_key(|&i| (std::cmp::Reverse(bucket(e[i as usize])), i));
        // Each entry's bucket's largest end: non-increasing, as partition_point needs.
        p.ends = pixels.iter().map(|&i| e[i as usize]).collect();
        for run in p.ends.chunk_by_mut(|a, b| bucket(*a) == bucket(*b)) {
            let most = run.iter().copied().max().unwrap_or(0);
            run.fill(most);
        }
        let last = p.ends.first().copied().unwrap_or(t.min_spp);
        self.ctx.write(ends, 0, &e)?;
        self.ctx.write(order, 0, &pixels)?;
        p.stop = Some(last.max(first));
        Ok(())
    }

    /// Dispatches `pass` samples from sample `from`, moving each block off the device when it
    /// completes; returns the samples done (fewer when cancelled).
    fn render_pass(
        &self,
        p: &mut Progress,
        seed: u64,
        from: u32,
        pass: u32,
        budget: u32,
        progress: &mut dyn FnMut(u32, u32),
    ) -> Result<u32> {
        let kernels = &self.setup.kernels;
        let mut k = 0;
        while k < pass {
            let s = from + k;
            let (block_start, block_end) = film::block_of(s, self.settings.spp);
            // With adaptive sampling, the pixels still sampling at s, packed: as few as they are,
            // a submission may take more samples of each.
            let active = p.stop.map(|_| p.ends.partition_point(|&e| e > s) as u32);
            let pixels = active.map_or(self.window.pixels() as u64, u64::from).max(1);
            let n = self
                .samples_per_submission(p, pixels)
                .min(pass - k)
                .min(block_end - s);
            // The integrator's own state (a cache generation) may end a dispatch early.
            let n = kernels.begin(self.ctx, seed, s, n)?.clamp(1, n);
            let dispatches = match active {
                Some(a) => packed(a, s, n, seed, interleaves_rows(self.ctx)),
                None => tiles(self.window, s, n, seed, interleaves_rows(self.ctx)),
            };
            // Every tile (or pack) of these samples in one submission: they write disjoint
            // pixels, so no barrier stands between them (IntegratorPasses::record).
            let started = Instant::now();
            self.ctx.one_shot(|cmd| {
                crate::vk::GpuTimer::around(self.timer, cmd, || {
                    for pc in &dispatches {
                        kernels.record(cmd, pc)
                    }
                })
            })?;
            let wall = started.elapsed().as_secs_f64();
            p.submissions += 1;
            p.rate = (pixels * u64::from(n)) as f64 / wall.max(1e-6);
            if let Some(t) = self.timer {
                p.device += t.seconds()?;
            }
            k += n;
            if s + n == block_end {
                let started = Instant::now();
                self.commit_block(p, block_start, block_end)?;
                p.commit += started.elapsed().as_secs_f64();
            }
            progress(p.done + k, budget);
            if self.cancelled() {
                // Every pixel has done + k samples: stop here, keeping them.
                p.interrupted = true;
                break;
            }
        }
        Ok(k)
    }

    /// Samples per pixel of the next submission over `pixels` pixels: at least the settings'
    /// samples_per_submit camera samples, and as many as the last submission's rate renders in
    /// [`SUBMIT_SECONDS`]; one where the driver cuts long loops short. The split changes no
    /// pixel: each pixel's samples are added in the same order however they are submitted.
    fn samples_per_submission(&self, p: &Progress, pixels: u64) -> u32 {
        if self.loop_limited {
            return 1;
        }
        let least = self.settings.samples_per_submit / pixels;
        let timed = (p.rate * SUBMIT_SECONDS) as u64 / pixels;
        least.max(timed).clamp(1, u64::from(film::FILM_BLOCK)) as u32
    }

    /// A complete block leaves the device: exact sums if the job owns all of it, else kept whole
    /// as a boundary block.
    fn commit_block(&self, p: &mut Progress, start: u32, end: u32) -> Result<()> {
        if start >= self.range.0 && end <= self.range.1 {
            return film::commit_block(self.ctx, self.film.device(), &mut p.sums);
        }
        let block = film::download_window(self.ctx, self.film.device(), self.window)?;
        p.sums.boundary.push(film::BoundaryBlock {
            start,
            end,
            sums: block,
        });
        film::clear(self.ctx, self.film.device())
    }

    /// The pass's row of the error-against-time report, evaluated when asked.
    fn report_pass(&self, p: &mut Progress) -> Result<()> {
        let (first, last) = (p.first, p.first + p.budget);
        let mut report = super::PassReport {
            pass: p.passes.len() as u32,
            spp: p.done,
            device_seconds: p.device,
            wall_seconds: p.wall,
            ..Default::default()
        };
        if !p.evaluate {
            p.passes.clear();
            p.passes.push(report);
            return Ok(());
        }
        // Reads the unfinished block without moving it: the block grid stays fixed.
        let mut peek = p.sums.all_sums();
        if (first + p.done) % film::FILM_BLOCK != 0 && first + p.done != last {
            let block = film::download_window(self.ctx, self.film.device(), self.window)?;
            film::add_block(peek.to_mut(), &block, p.sums.channels());
        }
        let r = film::resolve(
            &peek,
            &p.planes,
            (self.window.width(), self.window.height()),
            p.done,
            self.setup.split,
            (self.window.x0, self.window.y0),
        );
        evaluate_pass(&mut report, &r, self.settings.reference.as_deref());
        p.passes.push(report);
        p.last_resolved = Some(r);
        Ok(())
    }
}

/// One seed's render.
pub struct SeedOutput {
    /// The samples it holds of the job's range.
    pub range: (u32, u32),
    pub done: u32,
    pub wall: f64,
    pub device: f64,
    /// Of `wall`, the seconds spent moving complete blocks off the device.
    pub commit: f64,
    pub submissions: u64,
    pub interrupted: bool,
    pub sums: film::FilmSums,
    pub passes: Vec<super::PassReport>,
    pub resolved: film::Resolved,
}

pub fn evaluate_pass(
    report: &mut super::PassReport,
    r: &film::Resolved,
    reference: Option<&[[f32; 3]]>,
) {
    use crate::metrics;
    report.non_finite_samples = r.non_finite_samples;
    let variance = r.film.variance.as_deref().unwrap_or(&[]);
    report.estimated_relmse = metrics::estimated_relmse(
        &r.film.beauty,
        &r.even,
        &r.odd,
        &r.counts,
        &r.split,
        variance,
    );
    report.error = reference.map(|reference| metrics::compare(&r.film.beauty, reference));
}
