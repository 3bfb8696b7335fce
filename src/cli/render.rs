//! `illum render`: one scene to EXR (and PNG), with optional error reports.

use super::fast_start::{self, FastStart};
use super::progress::{announce_compiles, progress_bar};
use super::{DeviceArgs, IntegratorArgs, Interrupted, SceneArgs, check_outputs, signal};
use crate::film::Window;
use crate::output::image_metadata;
use crate::output::{write_exr, write_png};
use crate::render::{RenderSettings, Renderer};
use crate::vk::{Context, ContextOptions};
use anyhow::{Result, bail};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::Instant;

#[derive(clap::Args, Clone)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Output image: .exr (all layers), or .png (then the .exr is written beside it too).
    #[arg(short, long, default_value = "illum.exr")]
    pub output: PathBuf,
    /// Samples per pixel. [default: 16; with --time: no cap; with --noise-threshold: 4096, the
    /// most a pixel takes; with --adaptive: the budget, in samples a pixel]
    #[arg(long)]
    pub spp: Option<u32>,
    /// Adaptive sampling: each pixel stops once its estimated relative RMS error (from a pilot
    /// of --min-spp samples) is below this, e.g. 0.02 for 2%; the EXR then holds each pixel's
    /// count as SampleCount. [default: off]
    #[arg(long, value_name = "T", conflicts_with = "adaptive")]
    pub noise_threshold: Option<f64>,
    /// Adaptive sampling at a budget: the rays of --spp samples a pixel, spread over the pixels
    /// as their noise and the cost of their samples, measured by a pilot of --min-spp samples
    /// (the spread that minimises the image's relMSE), each pixel from 1/8 to 16 times --spp.
    #[arg(long)]
    pub adaptive: bool,
    /// With --noise-threshold or --adaptive: samples every pixel takes in the pilot that
    /// decides its count (a power of two, 2 to 128).
    #[arg(long, value_name = "N", default_value_t = crate::render::adaptive::Adaptive::DEFAULT_MIN_SPP)]
    pub min_spp: u32,
    /// Render for this many seconds (progressive passes) instead of a fixed sample count; --spp,
    /// if given, caps it.
    #[arg(long)]
    pub time: Option<f64>,
    /// Reference image (EXR, same resolution) to measure every pass against.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Write the error-against-time report, one row per pass (CSV).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Plot the error against time (log-log PNG).
    #[arg(long)]
    pub report_plot: Option<PathBuf>,
    /// Seed of the per-sample random streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    #[command(flatten)]
    pub gpu: DeviceArgs,
    /// Direct lighting by BRDF sampling (brdf), light sampling (light), or both with MIS (mis).
    /// [default: mis]
    #[arg(long, value_name = "TECHNIQUE")]
    pub technique: Option<String>,
    #[command(flatten)]
    pub integrator: IntegratorArgs,
    /// Host memory the film may take (e.g. 8G, 512MiB). A frame whose film would need more is
    /// rendered in bands of rows in turn (the same pixels) when its sample count is fixed, else
    /// refused before it starts. [default: the memory available]
    #[arg(long, value_name = "SIZE", value_parser = crate::film::memory::parse_bytes)]
    pub memory_limit: Option<u64>,
    /// Firefly clamp: scale down (keeping the hue) any camera sample whose direct lighting has a
    /// luminance above this. Biased when on (the summary and the EXR header say so). [default: off]
    #[arg(long)]
    pub clamp: Option<f32>,
    /// Also write an sRGB PNG of the beauty beside the EXR.
    #[arg(long)]
    pub png: bool,
    /// Add a `Denoised` layer to the EXR: the beauty denoised by Intel Open Image Denoise with
    /// the albedo and normal planes as guides (the beauty itself stays as rendered).
    #[arg(long)]
    pub denoise: bool,
    /// No progress bar, messages or summary (errors and warnings still print).
    #[arg(short, long)]
    pub quiet: bool,
    /// Enable the Vulkan validation layers (also on with ILLUM_VALIDATION=1).
    #[arg(long)]
    pub validate: bool,
    /// Render only samples A..B (A included, B excluded) of the --spp-sample image: one job of a
    /// split render, written as a partial EXR for `illum merge` (docs/farm.md).
    #[arg(long, value_name = "A..B", value_parser = parse_range)]
    pub samples: Option<(u32, u32)>,
    /// Render only the pixel window X0,Y0,X1,Y1 (X1, Y1 excluded): one job of a split render,
    /// written as a partial EXR for `illum merge`.
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = parse_crop)]
    pub crop: Option<Window>,
    /// Render part K of N (K from 0 to N-1, e.g. $SLURM_ARRAY_TASK_ID or $JOB_COMPLETION_INDEX)
    /// of the image as a partial EXR; `illum merge` of the N parts is bit-identical to the render
    /// in one piece, whatever N (docs/farm.md). [default --spp: 16, as a whole render]
    #[arg(long, value_name = "K/N", value_parser = super::part::parse_part,
          conflicts_with_all = ["samples", "crop"])]
    pub part: Option<(u32, u32)>,
    /// How --part cuts the image: samples (whole 256-sample blocks; row bands of a block when N
    /// exceeds the blocks) or tiles (a grid of N windows, every sample).
    #[arg(long, value_enum, default_value = "samples", requires = "part")]
    pub split: super::part::Split,
}

fn parse_range(s: &str) -> std::result::Result<(u32, u32), String> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| format!("{s:?} is not A..B"))?;
    let n = |x: &str| {
        x.trim()
            .parse::<u32>()
            .map_err(|_| format!("{x:?} in {s:?} is not a sample index"))
    };
    Ok((n(a)?, n(b)?))
}

impl RenderArgs {
    /// The sample grid (the most a pixel takes) and the adaptive sampling for `spp` samples
    /// asked.
    fn sampling(&self, spp: u32) -> (u32, Option<crate::render::adaptive::Adaptive>) {
        use crate::render::adaptive::{Adaptive, MEAN_CEILING};
        match self.noise_threshold {
            Some(t) => (spp, Some(Adaptive::threshold(t, self.min_spp))),
            None if self.adaptive => (
                spp.saturating_mul(MEAN_CEILING).min(crate::film::MAX_SPP),
                Some(Adaptive::mean(spp, self.min_spp)),
            ),
            None => (spp, None),
        }
    }

    /// These arguments with the image in `dir` (the second process of a fast start, which
    /// races only renders without a report or plot).
    fn staged(&self, dir: &Path) -> RenderArgs {
        let mut a = self.clone();
        a.output = fast_start::staged(dir, &self.output);
        a
    }

    /// The files a render reads, which no output may replace.
    fn inputs(&self) -> Vec<(&str, &Path)> {
        super::named([
            ("scene", self.scene.scene.as_deref()),
            ("reference", self.reference.as_deref()),
        ])
    }
}

fn parse_crop(s: &str) -> std::result::Result<Window, String> {
    let v: Vec<u32> = s
        .split(',')
        .map(|x| x.trim().parse::<u32>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| format!("{s:?} is not X0,Y0,X1,Y1 (pixel indices)"))?;
    let [x0, y0, x1, y1] = v[..] else {
        return Err(format!("{s:?} is not X0,Y0,X1,Y1 (four pixel indices)"));
    };
    Ok(Window { x0, y0, x1, y1 })
}

pub fn run(a: &RenderArgs) -> Result<()> {
    let cpu_at_start = fast_start::CpuTimes::now();
    let mode = fast_start::mode()?;
    // The second process of a fast start writes its image to the staging folder.
    let second = fast_start::staging().is_some();
    let staged;
    let asked = a;
    let a = match fast_start::staging() {
        Some(dir) => {
            staged = a.staged(&dir);
            &staged
        }
        None => a,
    };
    crate::output::check_writable(&a.output)?;
    if a.samples.is_some() || a.crop.is_some() || a.part.is_some() {
        return run_job(a);
    }
    let (exr_path, png_path) = super::image_paths(&a.output, a.png)?;
    // Every path is checked before anything slow (scene loading, device, kernels, rendering).
    if let Some(p) = &a.report_plot
        && !p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"))
    {
        bail!(
            "--report-plot {}: the plot is a PNG; name a .png file",
            p.display()
        );
    }
    let outputs = super::named([
        ("image", Some(exr_path.as_path())),
        ("PNG", png_path.as_deref()),
        ("report", a.report.as_deref()),
        ("plot", a.report_plot.as_deref()),
    ]);
    check_outputs(&outputs, &a.inputs())?;
    // The denoiser is loaded before the render: a missing library must not cost the render.
    let denoiser = a
        .denoise
        .then(crate::denoise::Denoiser::new)
        .transpose()
        .map_err(anyhow::Error::msg)?;
    let scene = a.scene.load()?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let reference = a
        .reference
        .as_deref()
        .map(|p| crate::output::read_reference(p, w, h))
        .transpose()?;
    let cancel = signal::install();
    let ctx = Context::new(&ContextOptions {
        device: a.gpu.device.clone(),
        validation: a.validate,
        ..Default::default()
    })?;
    let renderer = Renderer::new(ctx.clone());
    let spp = match (a.spp, a.time) {
        (Some(n), _) => n,
        (None, Some(_)) => 1 << 20,
        (None, None) if a.noise_threshold.is_some() => 4096,
        (None, None) if a.adaptive => 64,
        (None, None) => 16,
    };
    let (spp, adaptive) = a.sampling(spp);
    let settings = RenderSettings {
        integrator: a.integrator.integrator(&scene, a.technique.as_deref())?,
        spp,
        time: a.time,
        seed: a.seed,
        trace: a.gpu.trace,
        reference,
        evaluate_passes: a.report.is_some() || a.report_plot.is_some(),
        clamp: a.clamp,
        memory_limit: a.memory_limit,
        adaptive,
        cancel: Some(cancel),
        ..Default::default()
    };
    let bar = progress_bar(a.quiet, spp, a.time);
    // What decides the kernels, to note once they are in Mesa's cache (no race for them later).
    let key = fast_start::warm_key(&ctx, a.scene.scene.as_deref());
    // A fixed sample count only: under --time the two processes would render different images.
    // Not when passes are measured (--report, --report-plot, --reference): the error against
    // time would be the unoptimised kernels'.
    let race = (a.time.is_none() && !settings.evaluate_passes)
        .then(|| {
            // Where the second process writes the EXR and PNG (`staged` keeps the file names,
            // so the image paths of its output are these).
            let staged_outputs = |dir: &Path| {
                [Some(&exr_path), png_path.as_ref()]
                    .into_iter()
                    .flatten()
                    .map(|p| (fast_start::staged(dir, p), p.clone()))
                    .collect()
            };
            let pixels = u64::from(w) * u64::from(h);
            FastStart::start(
                mode,
                cpu_at_start,
                (&ctx, &key),
                fast_start::render_bytes(pixels, settings.evaluate_passes),
                staged_outputs,
                &bar,
            )
        })
        .flatten()
        .map(Arc::new);
    if mode == fast_start::Mode::Wait
        && let Some(r) = &race
    {
        // The tests' way to take the second process's path every time: it wins or fails
        // before this process compiles anything.
        r.take_over();
    }
    // The second process of a fast start says nothing until its result is taken; this one
    // stops it once its own kernels have compiled. A process that only compiles them for the
    // driver's cache (after a second process won) stops there.
    let compile_only = fast_start::compile_only();
    let optimised = !second;
    let (stop, racing) = (
        settings.cancel.clone().filter(|_| compile_only),
        race.clone(),
    );
    let compiled: Option<Box<dyn Fn() + Send + Sync>> = Some(Box::new(move || {
        if let Some(r) = &racing {
            r.take_over();
        }
        if optimised {
            fast_start::mark_warm(&key);
        }
        if let Some(s) = &stop {
            s.store(true, Ordering::SeqCst);
        }
    }));
    let setup_done = announce_compiles(&ctx, &bar, a.quiet || second, compiled);
    let started = Instant::now();
    let out = renderer.render(&scene, &settings, &mut |done, _| {
        if !setup_done.swap(true, Ordering::SeqCst) {
            bar.set_message("");
        }
        if let Some(t) = a.time {
            // Under a time budget the bar shows time, in per-mille of the budget.
            bar.set_position(((started.elapsed().as_secs_f64() / t) * 1000.0).min(1000.0) as u64);
        } else {
            bar.set_position(u64::from(done))
        }
    });
    setup_done.store(true, Ordering::SeqCst);
    if let Some(r) = &race {
        r.take_over();
    }
    ctx.set_kernel_listener(None);
    drop(race);
    bar.finish_and_clear();
    if compile_only {
        return Ok(());
    }
    let mut out = out?;
    let mut meta = image_metadata(&out, &settings, &ctx.info().name);
    if let Some(d) = &denoiser {
        d.add_layer(&mut out.film).map_err(anyhow::Error::msg)?;
        meta.extra.push(("illum.denoiser".into(), d.description()));
    }
    if second {
        // The image is the same; its timings are those of the unoptimised kernels.
        meta.extra.push((
            "illum.fastStart".into(),
            "rendered by the second process of a fast start, with the driver's unoptimised \
             kernels (GALLIVM_PERF=nopt)"
                .into(),
        ));
    }
    let s = &out.stats;
    if !s.dark_lights.is_empty() {
        crate::note!(
            "illum: note: left out lights that emit nothing (zero radiance or size): {}",
            s.dark_lights.join(", ")
        );
    }
    if s.emitters == 0 {
        crate::note!(
            "illum: warning: the scene emits no light (no light with radiance and size, no emissive \
             geometry): the image is black apart from the dome or emission seen directly"
        );
    }

    // The image first: a report or plot that fails to write must not lose it.
    write_exr(&exr_path, &out.film, &meta)?;
    if let Some(p) = &png_path {
        write_png(p, &out.film)?;
    }
    let mut failures = Vec::new();
    if let Some(p) = &a.report
        && let Err(e) = crate::report::write_csv(p, &out.passes)
    {
        failures.push(e.to_string());
    }
    if let Some(p) = &a.report_plot
        && let Err(e) = plot(p, &a.scene.name(), &out, settings.reference.is_some())
    {
        failures.push(e.to_string());
    }
    // The paths asked for (the second process of a fast start says where its image goes).
    let (shown_exr, shown_png) = super::image_paths(&asked.output, asked.png)?;
    let written = match &shown_png {
        Some(p) => format!("{} and {}", shown_exr.display(), p.display()),
        None => shown_exr.display().to_string(),
    };
    if !a.quiet {
        summary(&out, &scene, &ctx, &written, a.clamp);
    }
    if !failures.is_empty() {
        bail!("wrote {written}, but: {}", failures.join("; "));
    }
    super::check_validation(&ctx)?;
    if s.interrupted {
        return Err(Interrupted {
            signal: signal::received().unwrap_or(libc::SIGINT),
            wrote: true,
            kept: match s.bands {
                Some(b) if b.done < b.count => format!(
                    "wrote {written} with {} of {spp} samples per pixel in its first {} of {h} rows \
                     (the frame was rendered in bands); the rows after them have no sample \
                     (SampleCount 0)",
                    s.spp,
                    b.rows_done(h)
                ),
                _ => format!("wrote {written} with {} of {spp} samples per pixel", s.spp),
            },
        }
        .into());
    }
    Ok(())
}

fn plot(
    path: &std::path::Path,
    scene: &str,
    out: &crate::render::RenderOutput,
    measured: bool,
) -> crate::Result<()> {
    let (label, points): (&str, Vec<(f64, f64)>) = if measured {
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
    crate::report::plot_error(
        path,
        &format!("{scene}: error against time"),
        label,
        &[crate::report::Series {
            name: out.stats.trace.to_string(),
            points,
        }],
    )
}

fn summary(
    out: &crate::render::RenderOutput,
    scene: &crate::scene::Scene,
    ctx: &Context,
    written: &str,
    clamp: Option<f32>,
) {
    let s = &out.stats;
    let b = &s.build;
    let last = out.passes.last().cloned().unwrap_or_default();
    let samples = s.camera_samples as f64;
    let pixels = f64::from(scene.camera.width) * f64::from(scene.camera.height);
    let rows = s
        .bands
        .map_or(scene.camera.height, |b| b.rows_done(scene.camera.height));
    let spp = if rows < scene.camera.height {
        format!("{} in the first {rows} rows (interrupted)", s.spp)
    } else if s.camera_samples == pixels as u64 * u64::from(s.spp) + s.witness_samples {
        s.spp.to_string()
    } else {
        format!("{:.1} (adaptive, at most {})", samples / pixels, s.spp)
    };
    crate::note!(
        "illum: {}x{} at {} spp in {:.2} s on {} via {}: upload {:.3} s, structure build {:.3} s \
         ({} triangles; BLAS {:.1} MiB after compaction from {:.1}, TLAS {:.2} MiB), render {:.2} s \
         ({:.2} M camera samples/s, {:.2} M rays/s, {:.2} rays per sample; kernels {:.2} s on the device, {} submissions, \
         block commits {:.2} s); {} non-finite samples; wrote {}",
        scene.camera.width,
        scene.camera.height,
        spp,
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
        s.device_seconds,
        s.submissions,
        s.commit_seconds,
        s.non_finite_samples,
        written,
    );
    for (name, value) in &s.integrator {
        crate::note!("illum: {name}: {value}");
    }
    if let Some(b) = s.bands {
        crate::note!(
            "illum: the whole frame's film would not fit {} of memory: rendered in {} bands of {} \
             rows in turn (the same pixels)",
            crate::film::memory::format_bytes(b.budget),
            b.count,
            b.rows
        );
    }
    let mut line = format!(
        "illum: {} spp, {:.3} s rendering ({:.3} s on the device)",
        last.spp, last.wall_seconds, last.device_seconds
    );
    if s.interrupted {
        line += " (INTERRUPTED)";
    }
    if let Some(e) = last.error {
        line += &format!(
            ": relMSE {:.4e}, RMSE {:.4e}, MAE {:.4e} against the reference",
            e.relmse, e.rmse, e.mae
        );
    }
    if let Some(e) = last.estimated_relmse {
        line += &format!("; estimated relMSE {e:.4e} (half-buffers, blind to bias)");
    }
    if let Some(c) = clamp {
        line += &format!(
            "; BIASED: firefly clamp at luminance {c} reduced {} camera samples",
            s.clamped_samples
        );
    }
    crate::note!("{line}");
}

/// One job of a split render: samples A..B and/or a pixel window, or part K of N, written as a
/// partial EXR (src/jobs/partial.rs) that `illum merge` combines with the others, bit for bit.
fn run_job(a: &RenderArgs) -> Result<()> {
    let what = if a.part.is_some() {
        "--part"
    } else {
        "--samples and --crop"
    };
    let ext = a
        .output
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase());
    if ext.as_deref() != Some("exr") {
        bail!(
            "-o {}: a job of a split render ({what}) writes a partial EXR: name a .exr file",
            a.output.display()
        );
    }
    if a.time.is_some()
        || a.reference.is_some()
        || a.report.is_some()
        || a.report_plot.is_some()
        || a.png
        || a.denoise
    {
        bail!(
            "{what} render one job of an image: they take --spp, not --time, \
             --reference, --report, --report-plot, --png or --denoise (merge the jobs first)"
        );
    }
    let spp = match (a.spp, a.part) {
        (Some(n), _) => n,
        // A part of the default render (16 spp), like `illum render` without --spp.
        (None, Some(_)) => 16,
        (None, None) => {
            bail!("--samples and --crop need --spp: the samples per pixel of the whole image")
        }
    };
    let (spp, adaptive) = a.sampling(spp);
    check_outputs(&[("part", a.output.as_path())], &a.inputs())?;
    let scene = a.scene.load()?;
    let (samples, crop, label) = match a.part {
        Some((k, n)) => {
            let jobs = super::part::plan(n, a.split, spp, scene.camera.width, scene.camera.height)?;
            let j = jobs[k as usize];
            (
                Some(j.samples),
                Some(j.crop),
                format!("part {k}/{n} ({}), ", a.split.name()),
            )
        }
        None => (a.samples, a.crop, String::new()),
    };
    signal::set_part_job();
    let cancel = signal::install();
    let ctx = Context::new(&ContextOptions {
        device: a.gpu.device.clone(),
        validation: a.validate,
        ..Default::default()
    })?;
    let renderer = Renderer::new(ctx.clone());
    let settings = RenderSettings {
        integrator: a.integrator.integrator(&scene, a.technique.as_deref())?,
        spp,
        seed: a.seed,
        trace: a.gpu.trace,
        clamp: a.clamp,
        memory_limit: a.memory_limit,
        adaptive,
        cancel: Some(cancel),
        samples,
        crop,
        ..Default::default()
    };
    let bar = progress_bar(a.quiet, spp, None);
    let setup_done = announce_compiles(&ctx, &bar, a.quiet, None);
    let started = Instant::now();
    let out = renderer.render(&scene, &settings, &mut |done, budget| {
        if !setup_done.swap(true, Ordering::SeqCst) && !a.quiet {
            // A line for a farm's log: when set-up ended and what this job renders.
            let (s, w) = (
                samples.unwrap_or((0, spp)),
                crop.unwrap_or(Window::full(scene.camera.width, scene.camera.height)),
            );
            bar.suspend(|| {
                crate::note!(
                    "illum: {label}samples {}..{} of {spp}, pixels {w}: set-up done in {:.2} s, rendering",
                    s.0,
                    s.1,
                    started.elapsed().as_secs_f64()
                )
            });
        }
        bar.set_length(u64::from(budget));
        bar.set_position(u64::from(done));
    });
    setup_done.store(true, Ordering::SeqCst);
    ctx.set_kernel_listener(None);
    bar.finish_and_clear();
    let out = out?;
    if out.stats.interrupted {
        // A part is all or nothing: the scheduler reruns an interrupted job.
        return Err(Interrupted {
            signal: signal::received().unwrap_or(libc::SIGINT),
            wrote: false,
            kept: format!(
                "wrote nothing: a job is written only when complete ({} samples of its range were done); run it again",
                out.stats.spp
            ),
        }
        .into());
    }
    let info = crate::jobs::part_info(&scene, &settings, &out, &ctx.info().name)?;
    crate::jobs::partial::write_partial(&a.output, &info, &out.sums()?.sums)?;
    super::check_validation(&ctx)?;
    if !a.quiet {
        crate::note!(
            "illum: job {label}samples {}..{} of {spp}, pixels {} of {}x{}: {:.2} s rendering, {:.2} s set-up; wrote {}",
            info.samples.0,
            info.samples.1,
            info.window,
            info.frame.0,
            info.frame.1,
            info.render_seconds,
            info.setup_seconds,
            a.output.display()
        );
    }
    Ok(())
}
