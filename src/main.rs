//! The `illum` command line. It only parses arguments and calls the library.

use anyhow::{Context as _, Result, bail};
use clap::{Parser, Subcommand};
use illum::output::{ImageMetadata, write_exr, write_png};
use illum::render::{RenderSettings, Renderer};
use illum::trace::TraceMode;
use illum::vk::{Context, ContextOptions, list_devices};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};

#[derive(Parser)]
#[command(
    name = "illum",
    version,
    about = "Physically based rendering on Vulkan"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene (the embedded look-development scene when none is given).
    Render(RenderArgs),
    /// List the Vulkan devices, their drivers, memory and ray-query support.
    Devices,
    /// Print the JSON Schema of the scene format.
    Schema,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Scene file (.json); omit it to render the default scene.
    scene: Option<PathBuf>,
    /// Output image: .exr (multi-layer), or .png (writes the .exr beside it too).
    #[arg(short, long, default_value = "illum.exr")]
    output: PathBuf,
    /// Samples per pixel.
    #[arg(long, default_value_t = 16)]
    spp: u32,
    /// Seed of the per-sample random streams.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Override the camera's width (keeps the height unless --height is given).
    #[arg(long)]
    width: Option<u32>,
    #[arg(long)]
    height: Option<u32>,
    /// Device index or a substring of its name (see `illum devices`).
    #[arg(long)]
    device: Option<String>,
    /// Trace path: auto, rayquery or bvh.
    #[arg(long, default_value = "auto")]
    trace: TraceMode,
    /// Also write an sRGB PNG of the beauty beside the EXR.
    #[arg(long)]
    png: bool,
    /// No progress bar or summary.
    #[arg(short, long)]
    quiet: bool,
    /// Enable the Vulkan validation layers.
    #[arg(long)]
    validate: bool,
}

fn main() {
    if let Err(e) = run() {
        eprintln!("illum: error: {e:#}");
        std::process::exit(1);
    }
}

fn run() -> Result<()> {
    match Cli::parse().command {
        Command::Render(a) => render(a),
        Command::Devices => devices(),
        Command::Schema => {
            println!(
                "{}",
                serde_json::to_string_pretty(&illum::scene::json_schema())?
            );
            Ok(())
        }
    }
}

fn devices() -> Result<()> {
    let list = list_devices()?;
    if list.is_empty() {
        bail!("no Vulkan device found");
    }
    for d in list {
        println!(
            "{}: {} ({})\n    driver: {}\n    Vulkan {}, {:.1} GiB device-local memory, ray query: {}{}",
            d.index,
            d.name,
            d.kind,
            d.driver,
            d.api_version,
            d.device_local_memory as f64 / (1u64 << 30) as f64,
            if d.ray_query { "yes" } else { "no" },
            if d.missing.is_empty() {
                String::new()
            } else {
                format!("\n    unusable: lacks {}", d.missing.join(", "))
            }
        );
    }
    Ok(())
}

fn render(a: RenderArgs) -> Result<()> {
    let mut scene = match &a.scene {
        Some(p) => illum::scene::load(p)?,
        None => illum::scene::default_scene(),
    };
    match (a.width, a.height) {
        (Some(w), Some(h)) => (scene.camera.width, scene.camera.height) = (w, h),
        (Some(w), None) => {
            let aspect = f64::from(scene.camera.height) / f64::from(scene.camera.width);
            scene.camera.width = w;
            scene.camera.height = ((f64::from(w) * aspect).round() as u32).max(1);
        }
        (None, Some(h)) => {
            let aspect = f64::from(scene.camera.width) / f64::from(scene.camera.height);
            scene.camera.height = h;
            scene.camera.width = ((f64::from(h) * aspect).round() as u32).max(1);
        }
        (None, None) => {}
    }
    if scene.camera.width == 0 || scene.camera.height == 0 {
        bail!("--width and --height must be at least 1");
    }
    let ext = a
        .output
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase());
    let (exr_path, png_path) = match ext.as_deref() {
        Some("exr") => (
            a.output.clone(),
            a.png.then(|| a.output.with_extension("png")),
        ),
        Some("png") => (a.output.with_extension("exr"), Some(a.output.clone())),
        _ => bail!(
            "-o {}: the output must end in .exr or .png",
            a.output.display()
        ),
    };
    let ctx = Context::new(&ContextOptions {
        device: a.device.clone(),
        validation: a.validate,
    })?;
    let renderer = Renderer::new(ctx.clone());
    let settings = RenderSettings {
        spp: a.spp,
        seed: a.seed,
        trace: a.trace,
        ..Default::default()
    };
    let bar = if a.quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(u64::from(a.spp));
        b.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} spp (eta {eta})",
            )
            .unwrap(),
        );
        b
    };
    let out = renderer.render(&scene, &settings, &mut |done, _| {
        bar.set_position(u64::from(done))
    })?;
    bar.finish_and_clear();
    let meta = ImageMetadata {
        spp: a.spp,
        render_seconds: out.stats.total_seconds,
        device: ctx.info().name.clone(),
        seed: a.seed,
        extra: vec![
            ("illum.trace".into(), out.stats.trace.into()),
            (
                "illum.nonFiniteSamples".into(),
                out.stats.non_finite_samples.to_string(),
            ),
        ],
    };
    write(&exr_path, |p| write_exr(p, &out.film, &meta))?;
    if let Some(p) = &png_path {
        write(p, |p| write_png(p, &out.film))?;
    }
    if !a.quiet {
        let s = &out.stats;
        eprintln!(
            "illum: {}x{} at {} spp in {:.2} s (render {:.2} s, BLAS+TLAS {:.3} s) on {} via {}; {} non-finite samples; wrote {}{}",
            scene.camera.width,
            scene.camera.height,
            a.spp,
            s.total_seconds,
            s.render_seconds,
            s.build.blas_seconds + s.build.compaction_seconds + s.build.tlas_seconds,
            ctx.info().name,
            s.trace,
            s.non_finite_samples,
            exr_path.display(),
            png_path
                .map(|p| format!(" and {}", p.display()))
                .unwrap_or_default()
        );
    }
    let msgs = ctx.validation_messages();
    if !msgs.is_empty() {
        bail!("{} Vulkan validation message(s) (see above)", msgs.len());
    }
    Ok(())
}

fn write<E: std::error::Error + Send + Sync + 'static>(
    path: &Path,
    f: impl FnOnce(&Path) -> std::result::Result<(), E>,
) -> Result<()> {
    f(path).with_context(|| format!("writing {}", path.display()))
}
