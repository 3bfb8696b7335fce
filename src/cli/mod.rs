//! The `illum` command line, one module per command. `main.rs` only parses the arguments into a
//! [`Command`] and calls [`run`]; everything a command does lives here, on top of the library's
//! renderer, outputs and reports, which know nothing of the command line.

pub mod bench;
pub mod bench_lights;
pub mod compare;
pub mod devices;
pub mod merge;
pub mod part;
pub mod render;
pub mod schema;
mod signal;
pub mod stress;

use crate::output::ImageMetadata;
use crate::render::{RenderOutput, RenderSettings};
use crate::scene::Scene;
use anyhow::Result;
use clap::Subcommand;
use std::path::{Path, PathBuf};

#[derive(Subcommand)]
pub enum Command {
    /// Render a scene (the embedded look-development scene when none is given).
    Render(render::RenderArgs),
    /// Render a scene with several techniques for the same time and compare their error.
    Compare(compare::CompareArgs),
    /// List the Vulkan devices, their drivers, memory and ray-query support.
    Devices,
    /// Print the JSON Schema of the scene format.
    Schema,
    /// Benchmarks: figures to read, not tests.
    #[command(subcommand)]
    Bench(bench::BenchCommand),
    /// Render the stress suite (scenes/stress) and write its Markdown report.
    Stress(stress::StressArgs),
    /// Merge the jobs of a split render (partial EXRs of render --samples/--crop) into one image,
    /// bit-identical to rendering it in one piece.
    Merge(merge::MergeArgs),
}

/// Runs a command, prints its error if any, and returns the process exit status: 0, 1 for an
/// error (nothing, or not everything, was written), 128 + the signal number (130 for Ctrl-C,
/// 143 for SIGTERM) when a signal interrupted a render and the image of the samples done so far
/// was written; an interrupted part job writes nothing and exits 1.
pub fn run(command: Command) -> i32 {
    let result = match command {
        Command::Render(a) => render::run(&a),
        Command::Compare(a) => compare::run(&a),
        Command::Devices => devices::run(),
        Command::Schema => schema::run(),
        Command::Bench(b) => bench::run(&b),
        Command::Stress(a) => stress::run(&a),
        Command::Merge(a) => merge::run(&a),
    };
    match result {
        Ok(()) => 0,
        Err(e) => match e.downcast_ref::<Interrupted>() {
            Some(i) => {
                eprintln!("illum: {i}");
                if i.wrote { 128 + i.signal } else { 1 }
            }
            None => {
                eprintln!("illum: error: {e:#}");
                1
            }
        },
    }
}

/// A render stopped by SIGINT or SIGTERM.
#[derive(Debug)]
pub struct Interrupted {
    pub signal: i32,
    /// Whether the image of the samples done so far was written (the exit status says so).
    pub wrote: bool,
    /// What was kept, e.g. "wrote out.exr with 12 of 64 samples per pixel".
    pub kept: String,
}

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "interrupted by {}: {}",
            signal::name(self.signal),
            self.kept
        )
    }
}

impl std::error::Error for Interrupted {}

/// Scene file (or the default scene) and resolution override, shared by render and compare.
#[derive(clap::Args, Clone)]
pub struct SceneArgs {
    /// Scene file (.json); omit it for the embedded default scene (scenes/default.json).
    pub scene: Option<PathBuf>,
    /// Image width in pixels; the height follows the camera's aspect ratio unless --height is
    /// given too. [default: the scene camera's resolution]
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels; the width follows the camera's aspect ratio unless --width is
    /// given too. [default: the scene camera's resolution]
    #[arg(long)]
    pub height: Option<u32>,
}

impl SceneArgs {
    pub fn load(&self) -> Result<Scene> {
        let mut scene = match &self.scene {
            Some(p) => crate::scene::load(p)?,
            None => crate::scene::default_scene(),
        };
        scene.camera.set_resolution(self.width, self.height)?;
        Ok(scene)
    }

    /// The scene's name for titles: its file, or "default scene".
    pub fn name(&self) -> String {
        self.scene
            .as_ref()
            .map_or_else(|| "default scene".into(), |p| p.display().to_string())
    }
}

/// Sample counts of the direct-lighting integrator (the technique is chosen per command).
#[derive(clap::Args, Clone)]
pub struct IntegratorArgs {
    /// Most light samples per light (each light takes its solid-angle share of these, at least 1);
    /// 1 to 64.
    #[arg(long, default_value_t = 4)]
    pub light_samples: u32,
    /// BRDF samples per lobe; 1 to 64.
    #[arg(long, default_value_t = 2)]
    pub brdf_samples: u32,
    /// Diffuse lobe also by cosine-sampled BRDF samples, combined by MIS (off: light samples only,
    /// as in the course); `--diffuse-mis` alone is on, `--diffuse-mis=off` off. [default: off]
    #[arg(long, value_name = "MODE", num_args = 0..=1, require_equals = true, default_missing_value = "on", value_parser = ["on", "off"])]
    pub diffuse_mis: Option<String>,
    /// direct: direct lighting only; full: direct lighting, indirect diffuse through the radiosity
    /// cache, and reflections (caustics left out); path: brute-force path tracer (all light
    /// paths). [default: the scene's "integrator", else direct]
    #[arg(long, value_name = "KIND")]
    pub integrator: Option<crate::render::IntegratorKind>,
    /// path: the most path segments, as Mitsuba's max_depth (1: emission seen directly, 2: direct
    /// lighting, -1: unbounded). [default: the scene's, else -1]
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub max_depth: Option<i32>,
    /// full: the most specular bounces of the reflection integrator, 0 to 64. [default: the
    /// scene's, else 4]
    #[arg(long, value_name = "N")]
    pub specular_depth: Option<u32>,
    /// full: indirect diffuse through the radiosity cache (on) or by brute force (off), to
    /// measure the cache's bias and gain. [default: the scene's, else on]
    #[arg(long, value_name = "MODE", value_parser = ["on", "off"])]
    pub radiosity_cache: Option<String>,
    /// How light samples pick lights in scenes of more than 64 lights: tree (the light tree), scan
    /// (a linear scan over every light, as before the tree) or loop (every light at every point).
    #[arg(long, value_name = "KIND", default_value = "tree")]
    pub light_selection: crate::render::LightSelection,
    /// Trace shadow rays for this share (0 to 1] of each group's light and BRDF samples, picked by
    /// resampling on their unshadowed luminance, unbiased (docs/techniques.md,
    /// "Shadow resampling"); 1: all.
    #[arg(long, value_name = "PCT", default_value_t = 1.0)]
    pub shadow_resample: f32,
    /// Russian roulette before each shadow ray: keep a sample with probability min(1, its
    /// luminance / this), unbiased (docs/techniques.md, "Shadow culling"); 0: off.
    #[arg(long, value_name = "T", default_value_t = 0.0)]
    pub shadow_cull: f32,
    /// Control variates for diffuse light samples of looped rect, disk, sphere, triangle, sun and
    /// dome lights (textured ones with their mean radiance, a textured dome with its SH9
    /// projection, its sampler then drawing 10% of its samples uniformly; not lights picked from
    /// the tree): off, avgvis (the course's average visibility: biased, consistent) or loo (leave
    /// one out: unbiased).
    #[arg(long, value_name = "MODE", default_value = "off")]
    pub control_variates: crate::render::ControlVariates,
}

impl IntegratorArgs {
    /// The settings: these options, else the scene's `integrator` section, else the defaults.
    pub fn settings(
        &self,
        technique: crate::render::Technique,
        scene: &Scene,
    ) -> crate::render::IntegratorSettings {
        let d = crate::render::IntegratorSettings::default();
        let c = &scene.integrator;
        crate::render::IntegratorSettings {
            kind: self.integrator.or(c.kind).unwrap_or(d.kind),
            max_depth: self.max_depth.or(c.max_depth).unwrap_or(d.max_depth),
            specular_depth: self
                .specular_depth
                .or(c.specular_depth)
                .unwrap_or(d.specular_depth),
            radiosity_cache: self
                .radiosity_cache
                .as_deref()
                .map(|v| v == "on")
                .or(c.radiosity_cache)
                .unwrap_or(d.radiosity_cache),
            radiosity_refresh: d.radiosity_refresh,
            technique,
            light_samples: self.light_samples,
            brdf_samples: self.brdf_samples,
            diffuse_mis: self
                .diffuse_mis
                .as_deref()
                .map_or(d.diffuse_mis, |v| v == "on"),
            light_selection: self.light_selection,
            shadow_resample: self.shadow_resample,
            shadow_cull: self.shadow_cull,
            control_variates: self.control_variates,
        }
    }
}

/// The paths that are given, each with what it is ("image", "scene", ...): the lists
/// [`check_outputs`] takes.
pub fn named<'a, const N: usize>(
    paths: [(&'a str, Option<&'a Path>); N],
) -> Vec<(&'a str, &'a Path)> {
    paths
        .into_iter()
        .filter_map(|(what, p)| p.map(|p| (what, p)))
        .collect()
}

/// Checks every output path before any work (see [`crate::output::check_writable`]), and that no
/// output would replace an input or another output. Each path comes with what it is ("image",
/// "report", "scene", "reference", ...), for the error.
pub fn check_outputs(outputs: &[(&str, &Path)], inputs: &[(&str, &Path)]) -> Result<()> {
    for (_, p) in outputs {
        crate::output::check_writable(p)?;
    }
    crate::output::check_distinct(outputs, inputs)?;
    Ok(())
}

/// The image files of `-o OUTPUT`: the EXR always, and a PNG for `-o x.png` (the EXR beside it)
/// or with `--png`.
pub fn image_paths(output: &Path, png: bool) -> Result<(PathBuf, Option<PathBuf>)> {
    let ext = output
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase());
    Ok(match ext.as_deref() {
        Some("exr") => (
            output.to_path_buf(),
            png.then(|| output.with_extension("png")),
        ),
        Some("png") => (output.with_extension("exr"), Some(output.to_path_buf())),
        _ => anyhow::bail!(
            "-o {}: the output must end in .exr or .png",
            output.display()
        ),
    })
}

/// The EXR header of a render: what `illum render` and `illum compare` write alike.
pub fn image_metadata(
    out: &RenderOutput,
    settings: &RenderSettings,
    device: &str,
) -> ImageMetadata {
    let s = &out.stats;
    let it = &settings.integrator;
    let last = out.passes.last().cloned().unwrap_or_default();
    let mut extra = vec![
        ("illum.trace".to_string(), s.trace.to_string()),
        ("illum.integrator".into(), it.kind.name().into()),
        ("illum.technique".into(), it.technique.name().into()),
        ("illum.lightSamples".into(), it.light_samples.to_string()),
        ("illum.brdfSamples".into(), it.brdf_samples.to_string()),
        ("illum.diffuseMIS".into(), it.diffuse_mis.to_string()),
        (
            "illum.shadowResample".into(),
            it.shadow_resample.to_string(),
        ),
        ("illum.shadowCull".into(), it.shadow_cull.to_string()),
        (
            "illum.controlVariates".into(),
            it.control_variates.name().into(),
        ),
        (
            "illum.nonFiniteSamples".into(),
            s.non_finite_samples.to_string(),
        ),
        (
            "illum.deviceSeconds".into(),
            format!("{:.6}", s.device_seconds),
        ),
    ];
    if let Some(e) = last.estimated_relmse {
        extra.push(("illum.estimatedRelMSE".into(), format!("{e:.6e}")));
    }
    for (name, value) in &s.integrator {
        extra.push((format!("illum.{name}"), value.clone()));
    }
    if let Some(c) = settings.clamp {
        extra.push(("illum.fireflyClamp".into(), format!("{c} (biased)")));
        extra.push(("illum.clampedSamples".into(), s.clamped_samples.to_string()));
    }
    if let Some(e) = last.error {
        extra.push(("illum.relMSE".into(), format!("{:.6e}", e.relmse)));
        extra.push(("illum.RMSE".into(), format!("{:.6e}", e.rmse)));
        extra.push(("illum.MAE".into(), format!("{:.6e}", e.mae)));
    }
    if s.interrupted {
        extra.push(("illum.interrupted".into(), "true".into()));
        extra.push(("illum.sppRequested".into(), settings.spp.to_string()));
    }
    ImageMetadata {
        spp: s.spp,
        render_seconds: s.render_seconds,
        setup_seconds: s.setup_seconds,
        device: device.to_string(),
        seed: settings.seed,
        extra,
    }
}

/// Fails when the Vulkan validation layers reported anything.
pub fn check_validation(ctx: &crate::vk::Context) -> Result<()> {
    let msgs = ctx.validation_messages();
    if !msgs.is_empty() {
        anyhow::bail!("{} Vulkan validation message(s) (see above)", msgs.len());
    }
    Ok(())
}
