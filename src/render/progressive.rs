//! A render stepped by an interactive host (`illum view`): the blocking render's driver, set-up,
//! samples and film blocks, run a few samples at a time so that the host can show the image
//! between steps, move the camera or save. Its output after N samples of an `spp`-sample render
//! is the blocking render's at `spp` = N bit for bit (the device sums each block's samples in
//! index order whatever the steps, and blocks leave it into the same exact host sums).

use super::blocking::{Blocking, Progress};
use super::run::Run;
use super::{PreparedScene, RenderOutput, RenderSettings, Renderer};
use crate::error::Result;
use crate::film::{self, FilmSums};
use crate::scene::Camera;
use std::time::Instant;

pub struct Progressive<'p> {
    renderer: &'p Renderer,
    prepared: &'p PreparedScene,
    settings: RenderSettings,
    run: Option<Run>,
    progress: Progress,
    setup_seconds: f64,
    started: Instant,
    /// Which pixels of the window split their samples (film::Split; the same for every camera
    /// of the run's size and seed), for [`Peek`].
    split: Vec<bool>,
}

/// The sums of a render in progress as a host reads them for display: the exact sums of the
/// blocks that left the device, and the float32 sums of the block in progress.
pub struct Peek<'a> {
    pub sums: &'a FilmSums,
    pub block: Option<Vec<f32>>,
    /// Samples per pixel they hold.
    pub spp: u32,
    /// Which pixels of the window split their samples into the half-buffers (film::Split).
    pub split: &'a [bool],
}

impl Peek<'_> {
    /// Channel `c` of pixel `pixel` (row-major in the window), summed over the samples so far.
    pub fn channel(&self, pixel: usize, c: usize) -> f64 {
        let at = pixel * self.sums.channels() + c;
        let block = self.block.as_ref().map_or(0.0, |b| f64::from(b[at]));
        film::from_fixed(self.sums.sums[at], c) + block
    }
}

impl Renderer {
    /// A render of `prepared` through `camera` with `settings`, set up (kernels, film, warm-up
    /// dispatch) and at its first sample; [`Progressive::step`] renders it. The settings' job
    /// range, crop and time budget do not apply (the host decides when to stop).
    pub fn progressive<'p>(
        &'p self,
        prepared: &'p PreparedScene,
        camera: &Camera,
        settings: &RenderSettings,
    ) -> Result<Progressive<'p>> {
        let started = Instant::now();
        let settings = RenderSettings {
            time: None,
            samples: None,
            crop: None,
            ..settings.clone()
        };
        let (settings, _) = self.decide_allocation(prepared, camera, &settings)?;
        let run = Run::new(self, prepared, camera, &settings, 1)?;
        let blocking = run.blocking(self.context(), &settings);
        let progress = blocking.start(settings.seed)?;
        let w = blocking.window;
        let split = blocking
            .setup
            .split
            .window(w.x0, w.y0, w.width(), w.height());
        Ok(Progressive {
            renderer: self,
            prepared,
            setup_seconds: started.elapsed().as_secs_f64(),
            settings,
            run: Some(run),
            progress,
            started,
            split,
        })
    }
}

impl Progressive<'_> {
    fn run(&self) -> &Run {
        self.run
            .as_ref()
            .expect("the run lives as long as the render")
    }

    fn blocking(&self) -> Blocking<'_> {
        self.run().blocking(self.renderer.context(), &self.settings)
    }

    /// Samples per pixel done.
    pub fn done(&self) -> u32 {
        self.progress.done()
    }

    /// Whether every sample of the settings' `spp` is done.
    pub fn finished(&self) -> bool {
        self.done() >= self.settings.spp
    }

    /// Wall seconds of rendering since the last (re)start.
    pub fn wall_seconds(&self) -> f64 {
        self.progress.wall()
    }

    /// Renders `samples` more samples of every pixel (fewer if fewer are left); returns the
    /// samples per pixel done.
    pub fn step(&mut self, samples: u32) -> Result<u32> {
        let run = self
            .run
            .as_ref()
            .expect("the run lives as long as the render");
        run.blocking(self.renderer.context(), &self.settings).pass(
            &mut self.progress,
            samples,
            &mut |_, _| {},
        )?;
        Ok(self.done())
    }

    /// Starts afresh through `camera` (the same resolution): nothing of the scene is uploaded,
    /// the film is cleared.
    pub fn restart(&mut self, camera: &Camera) -> Result<()> {
        let ctx = self.renderer.context();
        let run = self
            .run
            .as_mut()
            .expect("the run lives as long as the render");
        run.set_camera(ctx, self.prepared, camera, &self.settings)?;
        self.progress = self.blocking().start(self.settings.seed)?;
        self.started = Instant::now();
        self.setup_seconds = 0.0;
        Ok(())
    }

    /// The sums so far, for display (reads the block in progress back from the device).
    pub fn peek(&self) -> Result<Peek<'_>> {
        Ok(Peek {
            sums: self.progress.sums(),
            block: self.blocking().block_in_progress(&self.progress)?,
            spp: self.done(),
            split: &self.split,
        })
    }

    /// The image so far as the blocking render would return it after this many samples (its
    /// film, statistics and exact sums), the render going on.
    pub fn output(&self) -> Result<RenderOutput> {
        let mut o = self.blocking().snapshot(&self.progress)?;
        // Short of the settings' spp, the image is what a render stopped here holds.
        o.interrupted = !self.finished();
        Ok(self.run().output(
            self.prepared,
            &self.settings,
            o,
            self.setup_seconds,
            self.started,
        ))
    }

    /// The settings the render runs with.
    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }
}

impl Drop for Progressive<'_> {
    fn drop(&mut self) {
        if let Some(run) = self.run.take() {
            run.keep(self.prepared);
        }
    }
}
