//! The `illum` command line, one module per command. `main.rs` only parses the arguments into a
//! [`Command`] and calls [`run`]; everything a command does lives here, on top of the library's
//! renderer, outputs and reports, which know nothing of the command line.

pub mod bench;
pub mod bench_lights;
pub mod compare;
pub mod devices;
mod fast_start;
pub mod merge;
pub mod part;
mod progress;
pub mod render;
pub mod schema;
mod signal;
pub mod stress;
pub mod view;

use crate::render::{Integrator, Params};
use crate::scene::Scene;
use anyhow::Result;
use clap::Subcommand;
use std::path::{Path, PathBuf};
use std::sync::Arc;

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
    /// Open a window that renders the scene progressively: the mouse moves the camera, edits of
    /// the scene file show at once, S saves the image (docs/view.md).
    View(view::ViewArgs),
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
        Command::View(a) => view::run(&a),
    };
    match result {
        Ok(()) => 0,
        Err(e) => match e.downcast_ref::<Interrupted>() {
            Some(i) => {
                crate::note!("illum: {i}");
                if i.wrote { 128 + i.signal } else { 1 }
            }
            None => {
                crate::note!("illum: error: {e:#}");
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

/// The device and trace path a command renders on: render, compare and view alike.
#[derive(clap::Args, Clone)]
pub struct DeviceArgs {
    /// Device index or a substring of its name (see `illum devices`). [default: the best device:
    /// discrete, integrated, virtual, then CPU]
    #[arg(long)]
    pub device: Option<String>,
    /// Trace path: auto (ray queries where the device has them), rayquery or bvh.
    #[arg(long, default_value = "auto")]
    pub trace: crate::trace::TraceMode,
}

/// Scene file (or the default scene) and resolution override, shared by render and compare.
#[derive(clap::Args, Clone)]
pub struct SceneArgs {
    /// Scene file: illum's JSON (.json) or a USD stage (.usd, .usda, .usdc, .usdz); omit it for
    /// the embedded default scene (scenes/default.json).
    pub scene: Option<PathBuf>,
    /// Image width in pixels; the height follows the camera's aspect ratio unless --height is
    /// given too. [default: the scene camera's resolution]
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels; the width follows the camera's aspect ratio unless --width is
    /// given too. [default: the scene camera's resolution]
    #[arg(long)]
    pub height: Option<u32>,
    /// Refuse a scene with warnings (what a USD stage holds that illum does not render) instead
    /// of printing them and rendering the rest.
    #[arg(long)]
    pub strict: bool,
}

impl SceneArgs {
    pub fn load(&self) -> Result<Scene> {
        let mut scene = match &self.scene {
            Some(p) => crate::scene::load(p)?,
            None => crate::scene::default_scene(),
        };
        if !scene.warnings.is_empty() {
            let list = scene.warnings.join("\n  ");
            if self.strict {
                anyhow::bail!(
                    "{}: --strict: {} warning(s):\n  {list}",
                    self.name(),
                    scene.warnings.len()
                );
            }
            crate::note!(
                "illum: {}: {} warning(s) (--strict refuses them):\n  {list}",
                self.name(),
                scene.warnings.len()
            );
        }
        scene
            .camera
            .set_resolution(self.width, self.height)
            .map_err(anyhow::Error::msg)?;
        Ok(scene)
    }

    /// The scene's name for titles: its file, or "default scene".
    pub fn name(&self) -> String {
        self.scene
            .as_ref()
            .map_or_else(|| "default scene".into(), |p| p.display().to_string())
    }
}

/// The integrator and its parameters. Each option here sets the parameter of its name (dashes
/// for underscores) of whichever integrator renders, which refuses one it does not take;
/// `--param NAME=VALUE` sets any.
#[derive(clap::Args, Clone)]
pub struct IntegratorArgs {
    /// direct: direct lighting only; full: direct lighting, indirect diffuse through the radiosity
    /// cache, and reflections, with caustic paths through specular lobes (`--param caustics=off`:
    /// the course's split, which leaves them out); path: brute-force path tracer (all light
    /// paths). [default: the scene's "integrator", else direct]
    #[arg(long, value_name = "NAME")]
    pub integrator: Option<String>,
    /// Most light samples per light (each light takes its solid-angle share of these, at least 1);
    /// 1 to 64. [default: 4]
    #[arg(long, value_name = "N")]
    pub light_samples: Option<u32>,
    /// BRDF samples per lobe; 1 to 64. [default: 2]
    #[arg(long, value_name = "N")]
    pub brdf_samples: Option<u32>,
    /// direct: how the light, BRDF and dome sample counts are chosen: auto (a pilot renders a
    /// small image under candidate counts and keeps the one with the least error × rays,
    /// docs/allocation.md) or fixed (the counts given, the course's rule). [default: auto,
    /// fixed when --light-samples or --brdf-samples is given]
    #[arg(long, value_name = "MODE", value_parser = ["auto", "fixed"])]
    pub allocation: Option<String>,
    /// Diffuse lobe also by cosine-sampled BRDF samples, combined by MIS (off: light samples only,
    /// as in the course); `--diffuse-mis` alone is on, `--diffuse-mis=off` off. [default: off]
    #[arg(long, value_name = "MODE", num_args = 0..=1, require_equals = true, default_missing_value = "on", value_parser = ["on", "off"])]
    pub diffuse_mis: Option<String>,
    /// path: the most path segments, as Mitsuba's max_depth (1: emission seen directly, 2: direct
    /// lighting, -1: unbounded). [default: -1]
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub max_depth: Option<i32>,
    /// full: the most specular bounces of the reflection integrator, 0 to 64. [default: 4]
    #[arg(long, value_name = "N")]
    pub specular_depth: Option<u32>,
    /// full: indirect diffuse through the radiosity cache (on) or by brute force (off), to
    /// measure the cache's bias and gain. [default: on]
    #[arg(long, value_name = "MODE", value_parser = ["on", "off"])]
    pub radiosity_cache: Option<String>,
    /// How light samples pick lights in scenes of more than 8 lights: auto (a loop up to 64
    /// lights, the tree above; `direct` measures which costs less up to 64), tree (the light
    /// tree), scan (a linear scan over every light, as before the tree) or loop (every light at
    /// every point). A choice other than auto keeps direct's counts fixed. [default: auto]
    #[arg(long, value_name = "KIND")]
    pub light_selection: Option<String>,
    /// Trace shadow rays for this share (0 to 1] of each group's light and BRDF samples, picked by
    /// resampling on their unshadowed luminance, unbiased (docs/techniques.md,
    /// "Shadow resampling"); 1: all. [default: 1]
    #[arg(long, value_name = "PCT")]
    pub shadow_resample: Option<f32>,
    /// Russian roulette before each shadow ray: keep a sample with probability min(1, its
    /// luminance / this), unbiased (docs/techniques.md, "Shadow culling"); 0: off. [default: 0]
    #[arg(long, value_name = "T")]
    pub shadow_cull: Option<f32>,
    /// Control variates for diffuse light samples of looped rect, disk, sphere, triangle, sun and
    /// dome lights (textured ones with their mean radiance, a textured dome with its SH9
    /// projection, its sampler then drawing 10% of its samples uniformly; not lights picked from
    /// the tree): off, avgvis (the course's average visibility: biased, consistent) or loo (leave
    /// one out: unbiased). [default: off]
    #[arg(long, value_name = "MODE")]
    pub control_variates: Option<String>,
    /// Any parameter of the integrator, NAME=VALUE (repeatable; docs/scene-format.md lists each
    /// integrator's).
    #[arg(long = "param", value_name = "NAME=VALUE")]
    pub params: Vec<String>,
}

impl IntegratorArgs {
    /// The integrator's name: this option, else the scene's, else the default.
    pub fn name(&self, scene: &Scene) -> String {
        crate::integrators::chosen(self.integrator.as_deref(), scene)
    }

    /// The parameters for integrator `name`: the scene's (when its section names that integrator
    /// or none), then these options over them.
    pub fn params(&self, name: &str, scene: &Scene) -> Result<Params> {
        let mut p = crate::integrators::scene_params(name, scene);
        let options: [(&str, Option<String>); 11] = [
            ("light_samples", self.light_samples.map(|v| v.to_string())),
            ("allocation", self.allocation.clone()),
            ("brdf_samples", self.brdf_samples.map(|v| v.to_string())),
            ("diffuse_mis", self.diffuse_mis.clone()),
            ("max_depth", self.max_depth.map(|v| v.to_string())),
            ("specular_depth", self.specular_depth.map(|v| v.to_string())),
            ("radiosity_cache", self.radiosity_cache.clone()),
            ("light_selection", self.light_selection.clone()),
            (
                "shadow_resample",
                self.shadow_resample.map(|v| v.to_string()),
            ),
            ("shadow_cull", self.shadow_cull.map(|v| v.to_string())),
            ("control_variates", self.control_variates.clone()),
        ];
        for (k, v) in options {
            if let Some(v) = v {
                p.set(k, v, format!("--{}", k.replace('_', "-")));
            }
        }
        for kv in &self.params {
            let Some((k, v)) = kv.split_once('=') else {
                anyhow::bail!("--param {kv:?}: expected NAME=VALUE");
            };
            p.set(k.trim(), v, format!("--param {kv}"));
        }
        Ok(p)
    }

    /// The integrator these options, the scene and the defaults name, with its parameters
    /// (and `technique`, from `--technique`, when given).
    pub fn integrator(
        &self,
        scene: &Scene,
        technique: Option<&str>,
    ) -> Result<Arc<dyn Integrator>> {
        let name = self.name(scene);
        let mut p = self.params(&name, scene)?;
        if let Some(t) = technique {
            p.set("technique", t, "--technique");
        }
        crate::integrators::create(&name, &p).map_err(|e| anyhow::anyhow!("{e}"))
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

/// Fails when the Vulkan validation layers reported anything.
pub fn check_validation(ctx: &crate::vk::Context) -> Result<()> {
    let msgs = ctx.validation_messages();
    if !msgs.is_empty() {
        anyhow::bail!("{} Vulkan validation message(s) (see above)", msgs.len());
    }
    Ok(())
}
