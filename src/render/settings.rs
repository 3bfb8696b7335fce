//! What a render is asked to do: the integrator (with its parameters) and the driver's settings
//! (samples, time, seed, trace path, job range and window, evaluation).

use super::Integrator;
use crate::error::{Error, Result};
use crate::film::Window;
use crate::trace::TraceMode;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

#[derive(Clone, Debug)]
pub struct RenderSettings {
    /// What renders, with its parameters (`crate::integrators`).
    pub integrator: Arc<dyn Integrator>,
    /// Samples per pixel: the budget, or the cap when `time` is set.
    pub spp: u32,
    /// Time budget in seconds of rendering (wall clock, evaluation excluded); None: `spp` only.
    pub time: Option<f64>,
    pub seed: u64,
    pub trace: TraceMode,
    /// Camera samples (pixels × samples) one submission takes at least; more once the device's
    /// rate is measured, up to what it renders in `driver::SUBMIT_SECONDS` (then a submission is
    /// short enough for any driver's watchdog, and its fixed costs stay small on a fast device).
    pub samples_per_submit: u64,
    /// Reference image (row-major RGB, the camera's resolution) to measure each pass against.
    pub reference: Option<Vec<[f32; 3]>>,
    /// Read the film back after every pass and evaluate it (implied by `reference`).
    pub evaluate_passes: bool,
    /// Firefly clamp: the most luminance one camera sample's direct lighting may have (scaled
    /// down, hue kept, above it). None: off, the default. It biases the image (docs/techniques.md,
    /// "Non-finite samples and the firefly clamp").
    pub clamp: Option<f32>,
    /// Set it (from another thread or a signal handler) to stop the render after the current
    /// round of dispatches: the output then holds the samples done so far (at least one per
    /// pixel) and says [`RenderStats::interrupted`].
    pub cancel: Option<Arc<AtomicBool>>,
    /// Test hook: make every n-th sample of each pixel NaN (0: off), to check that non-finite
    /// samples are counted and kept out of the image.
    #[doc(hidden)]
    pub inject_non_finite: u32,
    /// Render only samples [A, B) of the `spp`-sample image (a job of a split render; src/film/mod.rs).
    pub samples: Option<(u32, u32)>,
    /// Render only this pixel window.
    pub crop: Option<Window>,
    /// Host memory the film may take, in bytes (None: what the machine has available); a
    /// render that would need more is refused before it starts (src/film/memory.rs).
    pub memory_limit: Option<u64>,
    /// Adaptive sampling: each pixel's count decided from a pilot, by a noise threshold or as a
    /// mean spread by the pixels' noise (`spp` is then the most a pixel takes;
    /// src/render/adaptive.rs).
    pub adaptive: Option<super::adaptive::Adaptive>,
    /// Direct lighting's sample counts as decided (by the allocation pilot,
    /// src/render/allocation/), written over the integrator's; None: the integrator's own, or
    /// measured first when the integrator asks for that.
    pub allocation: Option<super::allocation::Allocation>,
}

impl RenderSettings {
    /// Checks the settings for an image of `width` x `height` pixels.
    pub fn check(&self, width: u32, height: u32) -> Result<()> {
        crate::film::check_spp(self.spp).map_err(Error::Invalid)?;
        if let Some(t) = self.time
            && !(t.is_finite() && t > 0.0)
        {
            return Err(Error::Invalid(format!(
                "--time must be a positive number of seconds, got {t}"
            )));
        }
        let (range, window) = self.job(width, height)?;
        let job = range != (0, self.spp) || window != Window::full(width, height);
        if job && (self.time.is_some() || self.reference.is_some()) {
            return Err(Error::Invalid(
                "a sample range or crop renders part of an image: it takes --spp, not --time or --reference".into(),
            ));
        }
        let pixels = u64::from(width) * u64::from(height);
        if let Some(r) = &self.reference
            && r.len() as u64 != pixels
        {
            return Err(Error::Invalid(format!(
                "the reference has {} pixels, the render {width}x{height} = {pixels}",
                r.len()
            )));
        }
        self.integrator.check().map_err(Error::Invalid)?;
        if let Some(t) = &self.adaptive {
            t.check(self.spp).map_err(Error::Invalid)?;
        }
        if let Some(c) = self.clamp
            && !(c.is_finite() && c > 0.0)
        {
            return Err(Error::Invalid(format!(
                "--clamp must be a positive finite luminance, got {c}"
            )));
        }
        Ok(())
    }

    /// The job's sample range and pixel window, checked against the image.
    pub fn job(&self, width: u32, height: u32) -> Result<((u32, u32), Window)> {
        let range = self.samples.unwrap_or((0, self.spp));
        if !(range.0 < range.1 && range.1 <= self.spp) {
            return Err(Error::Invalid(format!(
                "sample range {}..{} must be non-empty and within 0..{} (the image's spp)",
                range.0, range.1, self.spp
            )));
        }
        let window = self.crop.unwrap_or(Window::full(width, height));
        if !(window.x0 < window.x1
            && window.y0 < window.y1
            && window.x1 <= width
            && window.y1 <= height)
        {
            return Err(Error::Invalid(format!(
                "crop {window} must be a non-empty window within the {width}x{height} image"
            )));
        }
        Ok((range, window))
    }
}

/// 2^20 camera samples a submission, or ILLUM_SAMPLES_PER_SUBMIT (a measurement knob: how a
/// GPU's throughput depends on the work per submission, docs/performance-gpu.md).
fn samples_per_submit() -> u64 {
    std::env::var("ILLUM_SAMPLES_PER_SUBMIT")
        .ok()
        .and_then(|v| v.parse().ok())
        .filter(|&n| n > 0)
        .unwrap_or(1 << 20)
}

impl RenderSettings {
    /// The driver's defaults (16 spp, seed 0, any trace path) for `integrator`; the integrators'
    /// table provides `Default`, with the default integrator.
    pub fn with_integrator(integrator: Arc<dyn Integrator>) -> Self {
        RenderSettings {
            integrator,
            spp: 16,
            time: None,
            seed: 0,
            trace: TraceMode::Auto,
            samples_per_submit: samples_per_submit(),
            reference: None,
            evaluate_passes: false,
            clamp: None,
            cancel: None,
            inject_non_finite: 0,
            samples: None,
            crop: None,
            memory_limit: None,
            adaptive: None,
            allocation: None,
        }
    }
}
