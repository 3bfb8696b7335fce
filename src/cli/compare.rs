//! `illum compare`: several direct-lighting techniques rendered for the same time, with their
//! error table, error-against-time curves and an image strip with error heat-maps.

use super::render::{announce_compiles, progress_bar};
use super::{IntegratorArgs, Interrupted, SceneArgs, check_outputs, image_metadata, signal};
use crate::output::write_exr;
use crate::render::{PassReport, RenderOutput, RenderSettings, Renderer, Technique};
use crate::trace::TraceMode;
use crate::vk::{Context, ContextOptions};
use anyhow::{Result, bail};
use std::path::PathBuf;
use std::sync::atomic::Ordering;

#[derive(clap::Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Techniques to compare, comma separated, each once: brdf, light, mis.
    #[arg(long, default_value = "brdf,light,mis", value_delimiter = ',')]
    pub techniques: Vec<Technique>,
    /// Seconds of rendering per technique.
    #[arg(long, default_value_t = 5.0)]
    pub time: f64,
    /// Reference image (EXR, same resolution); without one, the relMSE is estimated from the
    /// even/odd half-buffers (blind to bias).
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Prefix of the outputs: PREFIX-error.png (curves), PREFIX-strip.png (images and error
    /// maps), PREFIX-<technique>.exr.
    #[arg(short, long, default_value = "compare")]
    pub output: PathBuf,
    /// Seed of the per-sample random streams (the same for every technique).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Device index or a substring of its name (see `illum devices`). [default: the best device]
    #[arg(long)]
    pub device: Option<String>,
    /// Trace path: auto (ray queries where the device has them), rayquery or bvh.
    #[arg(long, default_value = "auto")]
    pub trace: TraceMode,
    #[command(flatten)]
    pub integrator: IntegratorArgs,
    /// No progress bar or messages (the table still prints).
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(a: &CompareArgs) -> Result<()> {
    if a.techniques.is_empty() {
        bail!("--techniques: name at least one of brdf, light, mis");
    }
    for (i, t) in a.techniques.iter().enumerate() {
        if a.techniques[..i].contains(t) {
            bail!(
                "--techniques: {} is named twice (each technique renders once, to {}-{}.exr)",
                t.name(),
                a.output.display(),
                t.name()
            );
        }
    }
    let with_suffix = |s: &str| PathBuf::from(format!("{}-{s}", a.output.display()));
    let exr_of = |t: Technique| with_suffix(&format!("{}.exr", t.name()));
    let (plot_path, strip_path) = (with_suffix("error.png"), with_suffix("strip.png"));
    let exrs: Vec<PathBuf> = a.techniques.iter().map(|&t| exr_of(t)).collect();
    check_outputs(
        exrs.iter()
            .chain([&plot_path, &strip_path])
            .map(PathBuf::as_path),
    )?;
    let scene = a.scene.load()?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let reference = a
        .reference
        .as_deref()
        .map(|p| crate::output::read_reference(p, w, h))
        .transpose()?;
    let cancel = signal::install();
    let ctx = Context::new(&ContextOptions {
        device: a.device.clone(),
        validation: false,
    })?;
    let renderer = Renderer::new(ctx.clone());
    let mut rows: Vec<(Technique, RenderOutput)> = Vec::new();
    for (&t, exr) in a.techniques.iter().zip(&exrs) {
        let settings = RenderSettings {
            integrator: a.integrator.settings(t, &scene),
            spp: 1 << 20,
            time: Some(a.time),
            seed: a.seed,
            trace: a.trace,
            reference: reference.clone(),
            evaluate_passes: true,
            cancel: Some(cancel.clone()),
            ..Default::default()
        };
        if !a.quiet {
            eprintln!("illum compare: {} for {} s ...", t.name(), a.time);
        }
        let bar = progress_bar(a.quiet, settings.spp, Some(a.time));
        let setup_done = announce_compiles(&ctx, &bar, a.quiet);
        let started = std::time::Instant::now();
        let out = renderer.render(&scene, &settings, &mut |_, _| {
            if !setup_done.swap(true, Ordering::SeqCst) {
                bar.set_message("");
            }
            bar.set_position(
                ((started.elapsed().as_secs_f64() / a.time) * 1000.0).min(1000.0) as u64,
            );
        });
        setup_done.store(true, Ordering::SeqCst);
        ctx.set_kernel_listener(None);
        bar.finish_and_clear();
        let out = out?;
        write_exr(
            exr,
            &out.film,
            &image_metadata(&out, &settings, &ctx.info().name),
        )?;
        if out.stats.interrupted {
            // An interrupted technique had less time than the others: no fair comparison.
            return Err(Interrupted {
                signal: signal::received().unwrap_or(libc::SIGINT),
                kept: format!(
                    "wrote {} ({} spp); no table, curves or strip",
                    exr.display(),
                    out.stats.spp
                ),
            }
            .into());
        }
        rows.push((t, out));
    }
    let measured = reference.is_some();
    let error_of = |p: &PassReport| {
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
        series.push(crate::report::Series {
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
    crate::report::plot_error(
        &plot_path,
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
            Some(r) => crate::report::relative_error_map(&out.film.beauty, r),
            None => variance_map(out),
        })
        .collect();
    let panels: Vec<crate::report::Panel> = rows
        .iter()
        .zip(maps)
        .map(|((t, out), error)| crate::report::Panel {
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
    crate::report::image_strip(&strip_path, &panels)?;
    if !a.quiet {
        eprintln!(
            "illum compare: wrote {}, {} and {}-<technique>.exr",
            plot_path.display(),
            strip_path.display(),
            a.output.display()
        );
    }
    super::check_validation(&ctx)
}

/// Per-pixel variance of the mean over the squared pixel value: the half-buffer view of the
/// error, from the Variance AOV.
fn variance_map(out: &RenderOutput) -> Vec<f64> {
    let var = out.film.variance.as_ref();
    out.film
        .beauty
        .iter()
        .enumerate()
        .map(|(i, p)| {
            (0..3)
                .map(|c| {
                    let v = var.map_or(0.0, |v| f64::from(v[i][c]));
                    v / (f64::from(p[c]).powi(2) + crate::metrics::RELMSE_EPSILON)
                })
                .sum::<f64>()
                / 3.0
        })
        .collect()
}
