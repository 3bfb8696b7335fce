//! The direct-lighting integrator (glsl/direct/primary.comp, glsl/direct/direct.glsl): camera rays, the
//! AOVs, and emission plus direct lighting at the first hit, estimated as "Physically Based
//! Lighting at Pixar" does (docs/techniques.md, "The direct-lighting estimator"). Its parameters,
//! [`DirectLighting`], light every integrator's camera hits.

use crate::error::Result;
use crate::layout::*;
use crate::render::allocation::{AllocationMode, loop_affordable};
use crate::render::film_kernel::FilmKernel;
use crate::render::{Integrator, IntegratorPasses, Params, PreparedScene};
use crate::shaders;
use crate::vk::{Buffer, Context};
use ash::vk;

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

/// How light samples pick lights in a scene with a light tree (more than LIGHT_TREE_MIN_LIGHTS
/// lights; with fewer, every light is looped over).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LightSelection {
    /// A loop up to DIRECT_LOOP_LIGHTS lights, the tree above; where both can run, the
    /// allocation pilot measures which costs less (src/render/allocation/).
    #[default]
    Auto,
    /// Descend the light tree (docs/techniques.md, "The light tree"): O(log n) per sample.
    Tree,
    /// The former linear scan of a CDF over every light: O(n) per shading point (for comparison).
    Scan,
    /// Loop over every light at every shading point, each with its own samples (brute force).
    Loop,
}

impl LightSelection {
    pub fn name(self) -> &'static str {
        match self {
            LightSelection::Auto => "auto",
            LightSelection::Tree => "tree",
            LightSelection::Scan => "scan",
            LightSelection::Loop => "loop",
        }
    }
}

impl std::str::FromStr for LightSelection {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "auto" => Ok(LightSelection::Auto),
            "tree" => Ok(LightSelection::Tree),
            "scan" => Ok(LightSelection::Scan),
            "loop" => Ok(LightSelection::Loop),
            _ => Err(format!(
                "unknown light selection {s:?} (expected auto, tree, scan or loop)"
            )),
        }
    }
}

/// Control variates for the diffuse light samples of the looped lights (docs/techniques.md,
/// "Control variates"; glsl/direct/direct.glsl): the analytic unshadowed irradiance scaled by a
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

/// How camera hits are lit: the direct-lighting estimator's sample counts and switches, shared
/// by every integrator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectLighting {
    pub technique: Technique,
    /// Most light samples per light and camera sample; each light takes
    /// ceil(its solid-angle share of the hemisphere × this), at least 1 (the course's rule).
    pub light_samples: u32,
    /// BRDF samples per specular lobe (and for the diffuse lobe under BRDF sampling or diffuse MIS).
    pub brdf_samples: u32,
    /// Diffuse also by MIS with cosine-sampled BRDF samples (the course: light samples only).
    pub diffuse_mis: bool,
    /// A textured dome's light samples per light sample of other lights (it varies far more
    /// over its directions than any other light).
    pub dome_samples: u32,
    /// How light samples pick lights in a scene with a light tree.
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
    /// Whether the counts above are used as given (fixed, the default of a value built in code,
    /// which names its counts) or are where an allocation pilot starts (auto: the `direct`
    /// integrator's default when its parameters are parsed; src/render/allocation/).
    pub allocation: AllocationMode,
}

impl Default for DirectLighting {
    fn default() -> Self {
        DirectLighting {
            technique: Technique::Mis,
            light_samples: 4,
            brdf_samples: 2,
            diffuse_mis: false,
            dome_samples: 2,
            light_selection: LightSelection::Auto,
            shadow_resample: 1.0,
            shadow_cull: 0.0,
            control_variates: ControlVariates::Off,
            allocation: AllocationMode::Fixed,
        }
    }
}

impl DirectLighting {
    /// The parameters it reads.
    pub const PARAMS: &[&str] = &[
        "technique",
        "light_samples",
        "brdf_samples",
        "diffuse_mis",
        "dome_samples",
        "light_selection",
        "shadow_resample",
        "shadow_cull",
        "control_variates",
    ];

    /// Reads its parameters from `p` (the defaults for those not given) and checks them.
    pub fn parse(p: &Params) -> std::result::Result<DirectLighting, String> {
        let d = DirectLighting::default();
        let it = DirectLighting {
            technique: p.get("technique", d.technique)?,
            light_samples: p.get("light_samples", d.light_samples)?,
            brdf_samples: p.get("brdf_samples", d.brdf_samples)?,
            diffuse_mis: p.get_switch("diffuse_mis", d.diffuse_mis)?,
            dome_samples: p.get("dome_samples", d.dome_samples)?,
            light_selection: p.get("light_selection", d.light_selection)?,
            shadow_resample: p.get("shadow_resample", d.shadow_resample)?,
            shadow_cull: p.get("shadow_cull", d.shadow_cull)?,
            control_variates: p.get("control_variates", d.control_variates)?,
            allocation: d.allocation,
        };
        it.check()?;
        Ok(it)
    }

    pub fn check(&self) -> std::result::Result<(), String> {
        if !(1..=64).contains(&self.light_samples) || !(1..=64).contains(&self.brdf_samples) {
            return Err(format!(
                "light and BRDF sample counts must be in 1..=64, got {} and {}",
                self.light_samples, self.brdf_samples
            ));
        }
        if !(1..=16).contains(&self.dome_samples) {
            return Err(format!(
                "the dome's samples per light sample must be in 1..=16, got {}",
                self.dome_samples
            ));
        }
        if !(self.shadow_resample > 0.0 && self.shadow_resample <= 1.0) {
            return Err(format!(
                "the shadow resample share must be in (0, 1], got {}",
                self.shadow_resample
            ));
        }
        if !(self.shadow_cull >= 0.0 && self.shadow_cull.is_finite()) {
            return Err(format!(
                "the shadow cull threshold must be finite and at least 0, got {}",
                self.shadow_cull
            ));
        }
        if self.control_variates != ControlVariates::Off
            && (self.shadow_resample < 1.0 || self.shadow_cull > 0.0)
        {
            return Err(
                "control variates need every light sample's shadow ray: they do not \
                        combine with --shadow-resample or --shadow-cull"
                    .into(),
            );
        }
        Ok(())
    }

    /// The feature bits these settings add to the scene's in every kernel that lights with
    /// direct_lighting (code for what is off is left out).
    pub fn kernel_features(&self) -> u32 {
        let mut f = 0;
        if self.shadow_resample < 1.0 {
            f |= FEATURE_SHADOW_RESAMPLE;
        }
        if self.shadow_cull > 0.0 {
            f |= FEATURE_SHADOW_CULL;
        }
        if self.control_variates != ControlVariates::Off {
            f |= FEATURE_CONTROL_VARIATES;
        }
        f
    }

    /// Writes them into the frame constants.
    pub fn configure(&self, frame: &mut Frame) {
        frame.technique = match self.technique {
            Technique::Brdf => TECHNIQUE_BRDF,
            Technique::Light => TECHNIQUE_LIGHT,
            Technique::Mis => TECHNIQUE_MIS,
        };
        frame.light_samples = self.light_samples;
        frame.brdf_samples = self.brdf_samples;
        frame.dome_samples = self.dome_samples;
        frame.integrator_flags = if self.diffuse_mis {
            INTEGRATOR_DIFFUSE_MIS
        } else {
            0
        };
        frame.shadow_resample = self.shadow_resample;
        frame.shadow_cull = self.shadow_cull;
        frame.control_variates = match self.control_variates {
            ControlVariates::Off => 0,
            ControlVariates::AvgVis => CONTROL_VARIATES_AVGVIS,
            ControlVariates::Loo => CONTROL_VARIATES_LOO,
        };
        // Without a tree (few or no finite lights) every light is looped over.
        let tree = frame.light_tree != 0;
        frame.light_select = match self.light_selection {
            LightSelection::Tree if tree => LIGHT_SELECT_TREE,
            LightSelection::Auto if tree && !loop_affordable(frame) => LIGHT_SELECT_TREE,
            LightSelection::Scan => LIGHT_SELECT_SCAN,
            _ => LIGHT_SELECT_LOOP,
        };
    }

    /// Its part of an integrator's identity, after the integrator's own parameters.
    pub fn identity(&self, integrator: &str, own: &str) -> String {
        format!(
            "integrator={integrator} {own}technique={} light_samples={} brdf_samples={} diffuse_mis={} dome_samples={} lights={} shadow_resample={} shadow_cull={} control_variates={} allocation={}",
            self.technique.name(),
            self.light_samples,
            self.brdf_samples,
            self.diffuse_mis,
            self.dome_samples,
            self.light_selection.name(),
            self.shadow_resample,
            self.shadow_cull,
            self.control_variates.name(),
            self.allocation.name(),
        )
    }

    /// Its EXR header attributes.
    pub fn header(&self) -> Vec<(String, String)> {
        vec![
            ("technique".into(), self.technique.name().into()),
            ("lightSamples".into(), self.light_samples.to_string()),
            ("brdfSamples".into(), self.brdf_samples.to_string()),
            ("diffuseMIS".into(), self.diffuse_mis.to_string()),
            ("domeSamples".into(), self.dome_samples.to_string()),
            ("shadowResample".into(), self.shadow_resample.to_string()),
            ("shadowCull".into(), self.shadow_cull.to_string()),
            (
                "controlVariates".into(),
                self.control_variates.name().into(),
            ),
            ("allocationMode".into(), self.allocation.name().into()),
        ]
    }
}

/// Direct lighting with the course's sample counts and MIS.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Direct(pub DirectLighting);

impl Direct {
    /// Its parameters beyond the direct-lighting ones every integrator shares.
    pub const PARAMS: &[&str] = &["allocation"];

    /// Its parameters from `p`. The allocation is measured (auto) unless `p` says fixed, or
    /// names a sample count or the light selection without saying auto: counts given are counts
    /// meant.
    pub fn parse(p: &Params) -> std::result::Result<Direct, String> {
        let mut d = Direct(DirectLighting::parse(p)?);
        let counts_given = ["light_samples", "brdf_samples", "dome_samples"]
            .iter()
            .any(|n| p.has(n))
            || d.0.light_selection != LightSelection::Auto;
        let default = if counts_given {
            AllocationMode::Fixed
        } else {
            AllocationMode::Auto
        };
        d.0.allocation = p.get("allocation", default)?;
        p.finish("direct", &[Direct::PARAMS, DirectLighting::PARAMS].concat())?;
        Ok(d)
    }

    /// The default parameters with the allocation measured: what `direct` renders unless told
    /// otherwise.
    pub fn measured() -> Direct {
        Direct(DirectLighting {
            allocation: AllocationMode::Auto,
            ..DirectLighting::default()
        })
    }
}

impl Integrator for Direct {
    fn name(&self) -> &'static str {
        "direct"
    }

    fn check(&self) -> std::result::Result<(), String> {
        self.0.check()
    }

    fn configure(&self, frame: &mut Frame) {
        self.0.configure(frame);
    }

    fn features(&self) -> u32 {
        self.0.kernel_features()
    }

    fn kernels(&self, ctx: &Context, scene: &PreparedScene) -> Result<Box<dyn IntegratorPasses>> {
        Ok(Box::new(PrimaryKernel::new(
            ctx,
            scene,
            self.0.kernel_features(),
        )?))
    }

    fn identity(&self) -> String {
        self.0.identity("direct", "")
    }

    fn header(&self) -> Vec<(String, String)> {
        self.0.header()
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn measured_allocation(&self) -> bool {
        self.0.allocation == AllocationMode::Auto
    }
}

pub struct PrimaryKernel {
    kernel: FilmKernel,
}

impl PrimaryKernel {
    pub fn new(ctx: &Context, scene: &PreparedScene, features: u32) -> Result<PrimaryKernel> {
        let kernel = FilmKernel::new(
            ctx,
            scene,
            features,
            "primary",
            (shaders::PRIMARY_RQ, shaders::PRIMARY_BVH),
            false,
            std::mem::size_of::<PassConstants>(),
        )?;
        Ok(PrimaryKernel { kernel })
    }
}

impl IntegratorPasses for PrimaryKernel {
    fn bind(&self, frame: &Buffer, film: &Buffer, aovs: Option<&Buffer>) {
        self.kernel.bind(frame, film, aovs);
    }

    fn record(&self, cmd: vk::CommandBuffer, pass: &PassConstants) {
        self.kernel.dispatch_tile(cmd, pass);
    }
}
