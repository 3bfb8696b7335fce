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
    /// Benchmarks: figures to read, not tests.
    #[command(subcommand)]
    Bench(BenchCommand),
    /// Render a scene with several techniques for the same time and compare their error.
    Compare(CompareArgs),
    /// Render the stress suite (scenes/stress) and write its report (docs/stress.md).
    Stress(StressArgs),
}

#[derive(clap::Args)]
struct StressArgs {
    /// Directory of the stress scenes.
    #[arg(long, default_value = "scenes/stress")]
    scenes: PathBuf,
    /// The Markdown report to write.
    #[arg(short, long, default_value = "docs/stress.md")]
    output: PathBuf,
    /// Render time per case and trace path, in seconds.
    #[arg(long, default_value_t = 2.0)]
    time: f64,
    /// Image width and height of every case.
    #[arg(long, default_value_t = 64)]
    size: u32,
    /// Samples per pixel of the references rendered by a different technique.
    #[arg(long, default_value_t = 2048)]
    reference_spp: u32,
    /// Device index or a substring of its name (see `illum devices`).
    #[arg(long)]
    device: Option<String>,
}

/// Sample counts and the direct-lighting technique.
#[derive(clap::Args, Clone)]
struct IntegratorArgs {
    /// Direct lighting by BRDF sampling, light sampling, or both with MIS.
    #[arg(long, default_value = "mis")]
    technique: illum::render::Technique,
    /// Most light samples per light (each light takes its solid-angle share of these, at least 1).
    #[arg(long, default_value_t = 4)]
    light_samples: u32,
    /// BRDF samples per lobe.
    #[arg(long, default_value_t = 2)]
    brdf_samples: u32,
    /// Also combine cosine-sampled diffuse BRDF samples by MIS (the course: light samples only).
    #[arg(long)]
    diffuse_mis: bool,
}

impl IntegratorArgs {
    fn settings(&self, technique: illum::render::Technique) -> illum::render::IntegratorSettings {
        illum::render::IntegratorSettings {
            technique,
            light_samples: self.light_samples,
            brdf_samples: self.brdf_samples,
            diffuse_mis: self.diffuse_mis,
        }
    }
}

#[derive(clap::Args)]
struct CompareArgs {
    /// Scene file (.json); omit it to compare on the default scene.
    scene: Option<PathBuf>,
    /// Techniques to compare, comma separated (brdf, light, mis).
    #[arg(long, default_value = "brdf,light,mis", value_delimiter = ',')]
    techniques: Vec<illum::render::Technique>,
    /// Seconds of rendering per technique.
    #[arg(long, default_value_t = 5.0)]
    time: f64,
    /// Reference image (EXR, same resolution); without one, the half-buffer estimate is used.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Prefix of the outputs: PREFIX-error.png (curves), PREFIX-strip.png (images and error maps),
    /// PREFIX-<technique>.exr.
    #[arg(short, long, default_value = "compare")]
    output: PathBuf,
    #[arg(long)]
    width: Option<u32>,
    #[arg(long)]
    height: Option<u32>,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    #[arg(long)]
    device: Option<String>,
    #[arg(long, default_value = "auto")]
    trace: TraceMode,
    #[command(flatten)]
    integrator: IntegratorArgs,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Scene file (.json); omit it to render the default scene.
    scene: Option<PathBuf>,
    /// Output image: .exr (multi-layer), or .png (writes the .exr beside it too).
    #[arg(short, long, default_value = "illum.exr")]
    output: PathBuf,
    /// Samples per pixel (the cap when --time is given).
    #[arg(long)]
    spp: Option<u32>,
    /// Render for this many seconds (progressive passes) instead of a fixed sample count.
    #[arg(long)]
    time: Option<f64>,
    /// Reference image (EXR, same resolution) to measure every pass against.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Write the error-against-time report, one row per pass (CSV).
    #[arg(long)]
    report: Option<PathBuf>,
    /// Plot the error against time (log-log PNG).
    #[arg(long)]
    report_plot: Option<PathBuf>,
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
    /// Firefly clamp: scale down (keeping the hue) any camera sample whose direct lighting has a
    /// luminance above this. Off by default; biased when on (reported as such).
    #[arg(long)]
    clamp: Option<f32>,
    #[command(flatten)]
    integrator: IntegratorArgs,
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
        Command::Compare(a) => compare(a),
        Command::Stress(a) => stress(a),
        Command::Bench(BenchCommand::Trace(a)) => bench_trace(a),
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

fn load_scene(
    path: Option<&Path>,
    width: Option<u32>,
    height: Option<u32>,
) -> Result<illum::scene::Scene> {
    let mut scene = match path {
        Some(p) => illum::scene::load(p)?,
        None => illum::scene::default_scene(),
    };
    match (width, height) {
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
    Ok(scene)
}

fn read_reference(path: &Path, scene: &illum::scene::Scene) -> Result<Vec<[f32; 3]>> {
    let img = illum::output::read_exr(path)?;
    if (img.width, img.height) != (scene.camera.width, scene.camera.height) {
        bail!(
            "--reference {}: it is {}x{}, the render {}x{}",
            path.display(),
            img.width,
            img.height,
            scene.camera.width,
            scene.camera.height
        );
    }
    Ok(img.rgb()?)
}

fn compare(a: CompareArgs) -> Result<()> {
    let scene = load_scene(a.scene.as_deref(), a.width, a.height)?;
    if a.techniques.is_empty() {
        bail!("--techniques: name at least one of brdf, light, mis");
    }
    let reference = a
        .reference
        .as_deref()
        .map(|p| read_reference(p, &scene))
        .transpose()?;
    let ctx = Context::new(&ContextOptions {
        device: a.device.clone(),
        validation: false,
    })?;
    let renderer = Renderer::new(ctx.clone());
    let mut rows = Vec::new();
    for &t in &a.techniques {
        let settings = RenderSettings {
            integrator: a.integrator.settings(t),
            spp: 1 << 20,
            time: Some(a.time),
            seed: a.seed,
            trace: a.trace,
            reference: reference.clone(),
            evaluate_passes: true,
            ..Default::default()
        };
        eprintln!("illum compare: {} for {} s ...", t.name(), a.time);
        let out = renderer.render(&scene, &settings, &mut |_, _| {})?;
        let exr = PathBuf::from(format!("{}-{}.exr", a.output.display(), t.name()));
        let meta = ImageMetadata {
            spp: out.stats.spp,
            render_seconds: out.stats.render_seconds,
            setup_seconds: out.stats.setup_seconds,
            device: ctx.info().name.clone(),
            seed: a.seed,
            extra: vec![("illum.technique".into(), t.name().into())],
        };
        write(&exr, |p| write_exr(p, &out.film, &meta))?;
        rows.push((t, out));
    }
    let measured = reference.is_some();
    let error_of = |p: &illum::render::PassReport| {
        if measured {
            p.error.map(|e| e.relmse)
        } else {
            p.estimated_relmse
        }
    };
    println!(
        "{:<10} {:>8} {:>10} {:>14} {:>14}",
        "technique",
        "spp",
        "seconds",
        if measured { "relMSE" } else { "est. relMSE" },
        "efficiency"
    );
    let mut series = Vec::new();
    for (t, out) in &rows {
        let last = out.passes.last().cloned().unwrap_or_default();
        let err = error_of(&last).unwrap_or(f64::NAN);
        println!(
            "{:<10} {:>8} {:>10.3} {:>14.4e} {:>14.4e}",
            t.name(),
            last.spp,
            last.wall_seconds,
            err,
            1.0 / (err * last.wall_seconds)
        );
        series.push(illum::report::Series {
            name: t.name().to_string(),
            points: out
                .passes
                .iter()
                .filter_map(|p| Some((p.wall_seconds, error_of(p)?)))
                .collect(),
        });
    }
    if !measured {
        println!(
            "(no --reference: relMSE estimated from the even/odd half-buffers; the estimate cannot see bias)"
        );
    }
    let plot = PathBuf::from(format!("{}-error.png", a.output.display()));
    illum::report::plot_error(
        &plot,
        &format!("{:.1} s per technique", a.time),
        if measured {
            "relMSE"
        } else {
            "estimated relMSE (half-buffers)"
        },
        &series,
    )?;
    let maps: Vec<Vec<f64>> = rows
        .iter()
        .map(|(_, out)| match &reference {
            Some(r) => illum::report::relative_error_map(&out.film.beauty, r),
            None => {
                // Per-pixel variance of the mean over the squared pixel value: the half-buffer
                // view of the same error, from the Variance AOV.
                let var = out.film.variance.as_ref();
                out.film
                    .beauty
                    .iter()
                    .enumerate()
                    .map(|(i, p)| {
                        (0..3)
                            .map(|c| {
                                let v = var.map_or(0.0, |v| f64::from(v[i][c]));
                                v / (f64::from(p[c]).powi(2) + illum::metrics::RELMSE_EPSILON)
                            })
                            .sum::<f64>()
                            / 3.0
                    })
                    .collect()
            }
        })
        .collect();
    let panels: Vec<illum::report::Panel> = rows
        .iter()
        .zip(maps)
        .map(|((t, out), error)| illum::report::Panel {
            label: format!(
                "{} {}spp {:.1e}",
                t.name(),
                out.stats.spp,
                out.passes.last().and_then(error_of).unwrap_or(f64::NAN)
            ),
            film: &out.film,
            error,
        })
        .collect();
    let strip = PathBuf::from(format!("{}-strip.png", a.output.display()));
    illum::report::image_strip(&strip, &panels)?;
    eprintln!(
        "illum compare: wrote {}, {} and {}-<technique>.exr",
        plot.display(),
        strip.display(),
        a.output.display()
    );
    Ok(())
}

fn render(a: RenderArgs) -> Result<()> {
    let scene = load_scene(a.scene.as_deref(), a.width, a.height)?;
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
    let reference = a
        .reference
        .as_deref()
        .map(|p| read_reference(p, &scene))
        .transpose()?;
    let spp = match (a.spp, a.time) {
        (Some(n), _) => n,
        (None, Some(_)) => 1 << 20,
        (None, None) => 16,
    };
    let settings = RenderSettings {
        integrator: a.integrator.settings(a.integrator.technique),
        spp,
        time: a.time,
        seed: a.seed,
        trace: a.trace,
        reference,
        evaluate_passes: a.report.is_some() || a.report_plot.is_some(),
        clamp: a.clamp,
        ..Default::default()
    };
    let bar = if a.quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(u64::from(spp));
        b.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} spp (eta {eta})",
            )
            .unwrap(),
        );
        b
    };
    let started = std::time::Instant::now();
    let out = renderer.render(&scene, &settings, &mut |done, _| {
        if let Some(t) = a.time {
            // Under a time budget the bar shows time, in per-mille of the budget.
            bar.set_length(1000);
            bar.set_position(((started.elapsed().as_secs_f64() / t) * 1000.0).min(1000.0) as u64);
        } else {
            bar.set_position(u64::from(done))
        }
    })?;
    bar.finish_and_clear();
    if !out.stats.dark_lights.is_empty() {
        eprintln!(
            "illum: note: left out lights that emit nothing (zero radiance or size): {}",
            out.stats.dark_lights.join(", ")
        );
    }
    if out.stats.emitters == 0 {
        eprintln!(
            "illum: warning: the scene emits no light (no light with radiance and size, no emissive \
             geometry): the image is black apart from the dome or emission seen directly"
        );
    }
    let last = out.passes.last().cloned().unwrap_or_default();
    let mut extra = vec![
        ("illum.trace".to_string(), out.stats.trace.to_string()),
        (
            "illum.nonFiniteSamples".into(),
            out.stats.non_finite_samples.to_string(),
        ),
        (
            "illum.deviceSeconds".into(),
            format!("{:.6}", out.stats.device_seconds),
        ),
    ];
    if let Some(e) = last.estimated_relmse {
        extra.push(("illum.estimatedRelMSE".into(), format!("{e:.6e}")));
    }
    if let Some(c) = a.clamp {
        extra.push(("illum.fireflyClamp".into(), format!("{c} (biased)")));
        extra.push((
            "illum.clampedSamples".into(),
            out.stats.clamped_samples.to_string(),
        ));
    }
    if let Some(e) = last.error {
        extra.push(("illum.relMSE".into(), format!("{:.6e}", e.relmse)));
        extra.push(("illum.RMSE".into(), format!("{:.6e}", e.rmse)));
        extra.push(("illum.MAE".into(), format!("{:.6e}", e.mae)));
    }
    if let Some(p) = &a.report {
        illum::report::write_csv(p, &out.passes)?;
    }
    if let Some(p) = &a.report_plot {
        let (label, pts): (&str, Vec<(f64, f64)>) = if settings.reference.is_some() {
            (
                "relMSE",
                out.passes
                    .iter()
                    .filter_map(|p| Some((p.wall_seconds, p.error?.relmse)))
                    .collect(),
            )
        } else {
            (
                "estimated relMSE (half-buffers; blind to bias)",
                out.passes
                    .iter()
                    .filter_map(|p| Some((p.wall_seconds, p.estimated_relmse?)))
                    .collect(),
            )
        };
        let name = a
            .scene
            .as_ref()
            .map(|p| p.display().to_string())
            .unwrap_or_else(|| "default scene".into());
        illum::report::plot_error(
            p,
            &format!("{name}: error against time"),
            label,
            &[illum::report::Series {
                name: out.stats.trace.to_string(),
                points: pts,
            }],
        )?;
    }
    let meta = ImageMetadata {
        spp: out.stats.spp,
        render_seconds: out.stats.render_seconds,
        setup_seconds: out.stats.setup_seconds,
        device: ctx.info().name.clone(),
        seed: a.seed,
        extra,
    };
    write(&exr_path, |p| write_exr(p, &out.film, &meta))?;
    if let Some(p) = &png_path {
        write(p, |p| write_png(p, &out.film))?;
    }
    if !a.quiet {
        let s = &out.stats;
        let b = &s.build;
        let samples = f64::from(scene.camera.width)
            * f64::from(scene.camera.height)
            * f64::from(out.stats.spp);
        eprintln!(
            "illum: {}x{} at {} spp in {:.2} s on {} via {}: upload {:.3} s, structure build {:.3} s \
             ({} triangles; BLAS {:.1} MiB after compaction from {:.1}, TLAS {:.2} MiB), render {:.2} s \
             ({:.2} M camera samples/s, {:.2} M rays/s, {:.2} rays per sample); {} non-finite samples; wrote {}{}",
            scene.camera.width,
            scene.camera.height,
            out.stats.spp,
            s.total_seconds,
            ctx.info().name,
            s.trace,
            s.upload_seconds,
            b.blas_seconds + b.compaction_seconds + b.tlas_seconds,
            b.triangles,
            b.blas_bytes as f64 / 1048576.0,
            b.blas_bytes_uncompacted as f64 / 1048576.0,
            b.tlas_bytes as f64 / 1048576.0,
            s.render_seconds,
            samples / s.render_seconds / 1e6,
            s.rays as f64 / s.render_seconds / 1e6,
            s.rays as f64 / samples,
            s.non_finite_samples,
            exr_path.display(),
            png_path
                .map(|p| format!(" and {}", p.display()))
                .unwrap_or_default()
        );
        let mut line = format!(
            "illum: {} spp, {:.3} s rendering ({:.3} s on the device)",
            last.spp, last.wall_seconds, last.device_seconds
        );
        if let Some(e) = last.error {
            line += &format!(
                ": relMSE {:.4e}, RMSE {:.4e}, MAE {:.4e} against the reference",
                e.relmse, e.rmse, e.mae
            );
        }
        if let Some(e) = last.estimated_relmse {
            line += &format!("; estimated relMSE {e:.4e} (half-buffers, blind to bias)");
        }
        if let Some(c) = a.clamp {
            line += &format!(
                "; BIASED: firefly clamp at luminance {c} reduced {} camera samples",
                out.stats.clamped_samples
            );
        }
        eprintln!("{line}");
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

#[derive(Subcommand)]
enum BenchCommand {
    /// Ray throughput, build time and memory of the trace paths (ray queries, compute BVH) on
    /// procedurally generated meshes.
    Trace(BenchTraceArgs),
}

#[derive(clap::Args)]
struct BenchTraceArgs {
    /// Triangle counts of the procedural meshes, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "100000,1000000")]
    triangles: Vec<usize>,
    /// Rays per measurement.
    #[arg(long, default_value_t = 1 << 18)]
    rays: usize,
    /// Paths to measure: both, rayquery or bvh.
    #[arg(long, default_value = "both")]
    trace: String,
    /// Measurements of each figure; the best one is printed.
    #[arg(long, default_value_t = 3)]
    repeat: usize,
    /// Device index or a substring of its name (see `illum devices`).
    #[arg(long)]
    device: Option<String>,
    /// Enable the Vulkan validation layers.
    #[arg(long)]
    validate: bool,
}

fn bench_trace(a: BenchTraceArgs) -> Result<()> {
    use illum::trace::bench;
    let paths = match a.trace.as_str() {
        "both" => vec![TraceMode::RayQuery, TraceMode::Bvh],
        other => vec![other.parse::<TraceMode>().map_err(anyhow::Error::msg)?],
    };
    let ctx = Context::new(&ContextOptions {
        device: a.device.clone(),
        validation: a.validate,
    })?;
    if paths.contains(&TraceMode::RayQuery) && !ctx.ray_query() {
        eprintln!(
            "illum: {} has no VK_KHR_ray_query: measuring the compute BVH only",
            ctx.info().name
        );
    }
    println!(
        "device: {} ({}), {} rays per measurement, best of {}",
        ctx.info().name,
        ctx.info().driver,
        a.rays,
        a.repeat
    );
    println!(
        "{:>9} {:>8} | {:>8} {:>8} {:>8} | {:>13} {:>13} {:>13} | {:>5} {:>5}",
        "triangles",
        "path",
        "build ms",
        "BLAS MiB",
        "TLAS KiB",
        "primary",
        "bounce any",
        "bounce close",
        "hit%",
        "bnc%"
    );
    let rate = |r: bench::Rate| match r.cpu {
        Some(c) => format!("{:.3} ({:.3})", r.wall, c),
        None => format!("{:.3}", r.wall),
    };
    bench::run(
        &ctx,
        &bench::BenchOptions {
            triangles: a.triangles.clone(),
            rays: a.rays,
            paths,
            repeat: a.repeat,
        },
        &mut |r| {
            println!(
                "{:>9} {:>8} | {:>8.1} {:>8.2} {:>8.2} | {:>13} {:>13} {:>13} | {:>5.1} {:>5.1}",
                r.triangles,
                r.path,
                r.build.seconds() * 1e3,
                r.build.blas_bytes as f64 / 1048576.0,
                r.build.tlas_bytes as f64 / 1024.0,
                rate(r.primary),
                rate(r.bounce_any),
                rate(r.bounce_closest),
                r.primary_hits * 100.0,
                r.bounce_hits * 100.0
            )
        },
    )?;
    println!(
        "Mrays per second of wall time (and per CPU-second of this process, which other load on \
         the machine disturbs less); bounce rays: cosine-distributed from the first hits"
    );
    let msgs = ctx.validation_messages();
    if !msgs.is_empty() {
        bail!("{} Vulkan validation message(s) (see above)", msgs.len());
    }
    Ok(())
}

fn stress(a: StressArgs) -> Result<()> {
    let ctx = Context::new(&ContextOptions {
        device: a.device.clone(),
        validation: false,
    })?;
    let renderer = Renderer::new(ctx.clone());
    let o = illum::stress::StressOptions {
        seconds: a.time,
        width: a.size,
        height: a.size,
        reference_spp: a.reference_spp,
    };
    let rows = illum::stress::run(&renderer, &a.scenes, &o, &mut |r| {
        eprintln!(
            "illum stress: {:<24} {:<9} {:>7} spp  relMSE {:.2e}  non-finite {}  mean ratio {:.5} (z {:+.1})",
            r.case, r.trace, r.spp, r.relmse, r.non_finite_samples, r.mean_ratio, r.z
        )
    })?;
    let command = format!(
        "illum stress --time {} --size {} --reference-spp {}",
        a.time, a.size, a.reference_spp
    );
    let md = illum::stress::markdown(&rows, &o, &ctx.info().name, &command);
    std::fs::write(&a.output, md).with_context(|| format!("writing {}", a.output.display()))?;
    eprintln!("illum stress: wrote {}", a.output.display());
    Ok(())
}
