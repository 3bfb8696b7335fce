//! What a render is asked to do: the integrator's settings and the driver's (samples, time,
//! seed, trace path, job range and window, evaluation).

use super::film::Window;
use crate::error::{Error, Result};
use crate::trace::TraceMode;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

/// How direct lighting is estimated (docs/techniques.md, "The direct-lighting estimator").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Technique {
    /// BRDF sampling only: lights are found by the BRDF samples that hit them.
    Brdf,
    /// Light sampling only (delta lobes then see no light).
    Light,
    /// Both, combined by multiple importance sampling with the power heuristic.
    #[default]
    Mis,
}

impl Technique {
    pub fn name(self) -> &'static str {
        match self {
            Technique::Brdf => "brdf",
            Technique::Light => "light",
            Technique::Mis => "mis",
        }
    }
}

impl std::str::FromStr for Technique {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "brdf" => Ok(Technique::Brdf),
            "light" => Ok(Technique::Light),
            "mis" => Ok(Technique::Mis),
            _ => Err(format!(
                "unknown technique {s:?} (expected brdf, light or mis)"
            )),
        }
    }
}

/// Which integrator renders (src/render/integrator.rs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum IntegratorKind {
    /// Direct lighting only (emission seen directly, direct lighting at the camera hit).
    #[default]
    Direct,
    /// The seed's split: direct lighting, indirect diffuse through the radiosity cache, and the
    /// reflection integrator (docs/techniques.md, "Indirect lighting: the three integrators").
    Full,
    /// A brute-force unidirectional path tracer: the reference for `Full`.
    Path,
}

impl IntegratorKind {
    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::Direct => "direct",
            IntegratorKind::Full => "full",
            IntegratorKind::Path => "path",
        }
    }
}

/// How light samples pick lights when a scene has more than DIRECT_LOOP_LIGHTS of them
/// (glsl/lights/light_select.glsl).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LightSelection {
    /// Descend the light tree (docs/techniques.md, "The light tree"): O(log n) per sample.
    #[default]
    Tree,
    /// The former linear scan of a CDF over every light: O(n) per shading point (for comparison).
    Scan,
    /// Loop over every light at every shading point, each with its own samples (brute force).
    Loop,
}

impl LightSelection {
    pub fn name(self) -> &'static str {
        match self {
            LightSelection::Tree => "tree",
            LightSelection::Scan => "scan",
            LightSelection::Loop => "loop",
        }
    }
}

impl std::str::FromStr for IntegratorKind {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "direct" => Ok(IntegratorKind::Direct),
            "full" => Ok(IntegratorKind::Full),
            "path" => Ok(IntegratorKind::Path),
            _ => Err(format!(
                "unknown integrator {s:?} (expected direct, full or path)"
            )),
        }
    }
}

impl std::str::FromStr for LightSelection {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "tree" => Ok(LightSelection::Tree),
            "scan" => Ok(LightSelection::Scan),
            "loop" => Ok(LightSelection::Loop),
            _ => Err(format!(
                "unknown light selection {s:?} (expected tree, scan or loop)"
            )),
        }
    }
}

/// Control variates for the diffuse light samples of the looped lights (docs/techniques.md,
/// "Control variates"; glsl/direct/control_variates.glsl): the analytic unshadowed irradiance scaled by a
/// visibility estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ControlVariates {
    #[default]
    Off,
    /// The course's average visibility: biased (−Cov/N), consistent.
    AvgVis,
    /// Leave-one-out average visibility: unbiased.
    Loo,
}

impl ControlVariates {
    pub fn name(self) -> &'static str {
        match self {
            ControlVariates::Off => "off",
            ControlVariates::AvgVis => "avgvis",
            ControlVariates::Loo => "loo",
        }
    }
}

impl std::str::FromStr for ControlVariates {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "off" => Ok(ControlVariates::Off),
            "avgvis" => Ok(ControlVariates::AvgVis),
            "loo" => Ok(ControlVariates::Loo),
            _ => Err(format!(
                "unknown control variates {s:?} (expected off, avgvis or loo)"
            )),
        }
    }
}

/// The integrator and its sample counts and switches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IntegratorSettings {
    pub kind: IntegratorKind,
    /// `path`: the most path segments, as Mitsuba's `max_depth` (1: emission seen directly,
    /// 2: direct lighting); -1: unbounded (Russian roulette ends paths).
    pub max_depth: i32,
    /// `full`: the most specular bounces of the reflection integrator.
    pub specular_depth: u32,
    /// `full`: indirect diffuse through the radiosity cache (false: by brute force, the same
    /// partition without the cache, to measure its bias and gain).
    pub radiosity_cache: bool,
    /// `full`: new cache generations during the render, at samples 1, 2, 4, … (false: the
    /// warm-up's table serves every sample, as in a render session; src/render/session.rs).
    pub radiosity_refresh: bool,
    pub technique: Technique,
    /// Most light samples per light and camera sample; each light takes
    /// ceil(its solid-angle share of the hemisphere × this), at least 1 (the course's rule).
    pub light_samples: u32,
    /// BRDF samples per specular lobe (and for the diffuse lobe under BRDF sampling or diffuse MIS).
    pub brdf_samples: u32,
    /// Diffuse also by MIS with cosine-sampled BRDF samples (the course: light samples only).
    pub diffuse_mis: bool,
    /// How light samples pick lights above DIRECT_LOOP_LIGHTS lights.
    pub light_selection: LightSelection,
    /// Share of each group's shadow-ray candidates that get shadow rays, picked by systematic
    /// resampling on their unshadowed luminance (docs/techniques.md, "Shadow resampling"); 1: all,
    /// as without it.
    pub shadow_resample: f32,
    /// Russian roulette on each candidate before its shadow ray: kept with probability
    /// min(1, luminance / this), then divided by it (docs/techniques.md, "Shadow culling"); 0: off.
    pub shadow_cull: f32,
    /// Control variates for diffuse light samples (off: none).
    pub control_variates: ControlVariates,
}

impl IntegratorSettings {
    /// The feature bits these settings add to the scene's in every kernel that lights with
    /// direct_lighting (code for what is off is left out).
    pub fn kernel_features(&self) -> u32 {
        let mut f = 0;
        if self.shadow_resample < 1.0 {
            f |= crate::layout::FEATURE_SHADOW_RESAMPLE;
        }
        if self.shadow_cull > 0.0 {
            f |= crate::layout::FEATURE_SHADOW_CULL;
        }
        if self.control_variates != ControlVariates::Off {
            f |= crate::layout::FEATURE_CONTROL_VARIATES;
        }
        f
    }
}

impl Default for IntegratorSettings {
    fn default() -> Self {
        IntegratorSettings {
            kind: IntegratorKind::Direct,
            max_depth: -1,
            specular_depth: 4,
            radiosity_cache: true,
            radiosity_refresh: true,
            technique: Technique::Mis,
            light_samples: 4,
            brdf_samples: 2,
            diffuse_mis: false,
            light_selection: LightSelection::Tree,
            shadow_resample: 1.0,
            shadow_cull: 0.0,
            control_variates: ControlVariates::Off,
        }
    }
}

#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub integrator: IntegratorSettings,
    /// Samples per pixel: the budget, or the cap when `time` is set.
    pub spp: u32,
    /// Time budget in seconds of rendering (wall clock, evaluation excluded); None: `spp` only.
    pub time: Option<f64>,
    pub seed: u64,
    pub trace: TraceMode,
    /// Upper bound on camera samples (pixels × samples) in one submission, so that no dispatch
    /// runs long enough to trip a desktop driver's watchdog.
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
    /// Render only samples [A, B) of the `spp`-sample image (a job of a split render; film.rs).
    pub samples: Option<(u32, u32)>,
    /// Render only this pixel window.
    pub crop: Option<Window>,
}

impl RenderSettings {
    /// Checks the settings for an image of `width` x `height` pixels.
    pub fn check(&self, width: u32, height: u32) -> Result<()> {
        super::film::check_spp(self.spp).map_err(Error::Invalid)?;
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
        let it = &self.integrator;
        if !(1..=64).contains(&it.light_samples) || !(1..=64).contains(&it.brdf_samples) {
            return Err(Error::Invalid(format!(
                "light and BRDF sample counts must be in 1..=64, got {} and {}",
                it.light_samples, it.brdf_samples
            )));
        }
        if !(it.shadow_resample > 0.0 && it.shadow_resample <= 1.0) {
            return Err(Error::Invalid(format!(
                "the shadow resample share must be in (0, 1], got {}",
                it.shadow_resample
            )));
        }
        if !(it.shadow_cull >= 0.0 && it.shadow_cull.is_finite()) {
            return Err(Error::Invalid(format!(
                "the shadow cull threshold must be finite and at least 0, got {}",
                it.shadow_cull
            )));
        }
        if it.control_variates != ControlVariates::Off
            && (it.shadow_resample < 1.0 || it.shadow_cull > 0.0)
        {
            return Err(Error::Invalid(
                "control variates need every light sample's shadow ray: they do not combine \
                 with --shadow-resample or --shadow-cull"
                    .into(),
            ));
        }
        if it.max_depth == 0 || it.max_depth < -1 {
            return Err(Error::Invalid(format!(
                "--max-depth counts path segments: -1 (unbounded) or at least 1, got {}",
                it.max_depth
            )));
        }
        if it.specular_depth > 64 {
            return Err(Error::Invalid(format!(
                "--specular-depth must be in 0..=64, got {}",
                it.specular_depth
            )));
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

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            integrator: IntegratorSettings::default(),
            spp: 16,
            time: None,
            seed: 0,
            trace: TraceMode::Auto,
            samples_per_submit: 1 << 20,
            reference: None,
            evaluate_passes: false,
            clamp: None,
            cancel: None,
            inject_non_finite: 0,
            samples: None,
            crop: None,
        }
    }
}
