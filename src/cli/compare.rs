//! `illum compare`: several integrators or direct-lighting techniques rendered for the same time,
//! with their error table, error-against-time curves and an image strip with error heat-maps.

use super::progress::{announce_compiles, progress_bar};
use super::{DeviceArgs, IntegratorArgs, Interrupted, SceneArgs, check_outputs, signal};
use crate::compare::{Budget, Comparison, Run, Samples, Spec, parse_samples};
use crate::integrators::Technique;
use crate::output::image_metadata;
use crate::output::write_exr;
use crate::render::{RenderOutput, RenderSettings, Renderer};
use crate::vk::{Context, ContextOptions};
use anyhow::Result;
use std::path::PathBuf;
use std::sync::atomic::Ordering;

#[derive(clap::Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Techniques to compare, comma separated, each once: brdf, light, mis. [default:
    /// brdf,light,mis; mis with --integrators]
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    pub techniques: Option<Vec<Technique>>,
    /// Integrators to compare, comma separated, each once: any of `illum render --integrator`
    /// (direct, full, path), full-nocache (the full integrator's partition by brute force,
    /// --radiosity-cache off) or full-nocaustics (the course's split, --param caustics=off). Each
    /// renders with each technique. [default: the one --integrator names]
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    pub integrators: Vec<String>,
    /// Sample allocations to compare, comma separated: L/B (light samples / BRDF samples per
    /// lobe, diffuse MIS as --diffuse-mis says), L/B/dmis (diffuse MIS on) or L/B/nodmis (off),
    /// e.g. 4/2/nodmis,1/1/dmis: how the defaults were chosen (docs/performance-sampling.md). Each renders
    /// with each technique and integrator. [default: the one the options name]
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = parse_samples)]
    pub samples: Vec<Samples>,
    /// Seconds of rendering per technique or integrator.
    #[arg(long, default_value_t = 5.0)]
    pub time: f64,
    /// Reference image (EXR, same resolution); without one, the relMSE is estimated from the
    /// even/odd half-buffers (blind to bias).
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Prefix of the outputs: PREFIX-error.png (curves), PREFIX-strip.png (images and error
    /// maps), PREFIX-<name>.exr (a technique's or integrator's name).
    #[arg(short, long, default_value = "compare")]
    pub output: PathBuf,
    /// Seed of the per-sample random streams (the same for every technique).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    #[command(flatten)]
    pub gpu: DeviceArgs,
    #[command(flatten)]
    pub integrator: IntegratorArgs,
    /// No progress bar or messages (the table still prints).
    #[arg(short, long)]
    pub quiet: bool,
}

/// The files a comparison writes: one EXR per run, the error plot and the image strip.
struct Outputs {
    exrs: Vec<PathBuf>,
    plot: PathBuf,
    strip: PathBuf,
}

impl Outputs {
    /// The files of `runs`, checked before any work.
    fn new(a: &CompareArgs, runs: &[Run]) -> Result<Outputs> {
        let with_suffix = |s: &str| PathBuf::from(format!("{}-{s}", a.output.display()));
        let o = Outputs {
            exrs: runs
                .iter()
                .map(|r| with_suffix(&format!("{}.exr", r.name)))
                .collect(),
            plot: with_suffix("error.png"),
            strip: with_suffix("strip.png"),
        };
        let outputs: Vec<(&str, &std::path::Path)> = o
            .exrs
            .iter()
            .map(|p| ("image", p.as_path()))
            .chain([("plot", o.plot.as_path()), ("strip", o.strip.as_path())])
            .collect();
        let inputs = super::named([
            ("scene", a.scene.scene.as_deref()),
            ("reference", a.reference.as_deref()),
        ]);
        check_outputs(&outputs, &inputs)?;
        Ok(o)
    }
}

/// The comparison's runs, as the options name them.
fn spec<'a>(
    a: &'a CompareArgs,
    scene: &crate::scene::Scene,
    params: &'a dyn Fn(&str) -> Result<crate::render::Params, String>,
) -> Spec<'a> {
    Spec {
        techniques: a.techniques.clone(),
        integrators: a.integrators.clone(),
        samples: a.samples.clone(),
        default_integrator: a.integrator.name(scene),
        params,
        arg: |n| format!("--{n}"),
    }
}

pub fn run(a: &CompareArgs) -> Result<()> {
    let scene = a.scene.load()?;
    let params = |kind: &str| {
        a.integrator
            .params(kind, &scene)
            .map_err(|e| format!("{e:#}"))
    };
    let spec = spec(a, &scene, &params);
    let runs = spec.runs()?;
    let files = Outputs::new(a, &runs)?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let reference = a
        .reference
        .as_deref()
        .map(|p| crate::output::read_reference(p, w, h))
        .transpose()?;
    let cancel = signal::install();
    let ctx = Context::new(&ContextOptions {
        device: a.gpu.device.clone(),
        validation: false,
        ..Default::default()
    })?;
    let renderer = Renderer::new(ctx.clone());
    let budget = Budget {
        time: a.time,
        seed: a.seed,
        trace: a.gpu.trace,
        reference: reference.clone(),
        cancel: Some(cancel.clone()),
    };
    let mut cmp = Comparison {
        runs: Vec::new(),
        measured: reference.is_some(),
        time: a.time,
    };
    for (run, exr) in runs.iter().zip(&files.exrs) {
        let settings = budget.settings(run);
        let out = render_run(a, &renderer, &scene, &settings, &run.name)?;
        write_exr(
            exr,
            &out.film,
            &image_metadata(&out, &settings, &ctx.info().name),
        )?;
        if out.stats.interrupted {
            // An interrupted technique had less time than the others: no fair comparison.
            return Err(Interrupted {
                signal: signal::received().unwrap_or(libc::SIGINT),
                wrote: true,
                kept: format!(
                    "wrote {} ({} spp); no table, curves or strip",
                    exr.display(),
                    out.stats.spp
                ),
            }
            .into());
        }
        cmp.runs.push((run.name.clone(), out));
    }
    print_table(spec.kind(), &cmp);
    cmp.write_plot(&files.plot)?;
    cmp.write_strip(&files.strip, reference.as_deref())?;
    if !a.quiet {
        crate::note!(
            "illum compare: wrote {}, {} and {}-<name>.exr",
            files.plot.display(),
            files.strip.display(),
            a.output.display()
        );
    }
    super::check_validation(&ctx)
}

/// One run's render, with its progress bar.
fn render_run(
    a: &CompareArgs,
    renderer: &Renderer,
    scene: &crate::scene::Scene,
    settings: &RenderSettings,
    name: &str,
) -> Result<RenderOutput> {
    if !a.quiet {
        crate::note!("illum compare: {name} for {} s ...", a.time);
    }
    let ctx = renderer.context();
    let bar = progress_bar(a.quiet, settings.spp, Some(a.time));
    let setup_done = announce_compiles(ctx, &bar, a.quiet, None);
    let started = std::time::Instant::now();
    let out = renderer.render(scene, settings, &mut |_, _| {
        if !setup_done.swap(true, Ordering::SeqCst) {
            bar.set_message("");
        }
        bar.set_position(((started.elapsed().as_secs_f64() / a.time) * 1000.0).min(1000.0) as u64);
    });
    setup_done.store(true, Ordering::SeqCst);
    ctx.set_kernel_listener(None);
    bar.finish_and_clear();
    Ok(out?)
}

/// Prints the table of runs.
fn print_table(kind: &str, cmp: &Comparison) {
    println!(
        "{:<14} {:>8} {:>10} {:>14} {:>14}",
        kind,
        "spp",
        "seconds",
        if cmp.measured {
            "relMSE"
        } else {
            "est. relMSE"
        },
        "efficiency"
    );
    for r in cmp.rows() {
        println!(
            "{:<14} {:>8} {:>10.3} {:>14.4e} {:>14.4e}",
            r.name, r.spp, r.seconds, r.relmse, r.efficiency
        );
    }
    if !cmp.measured {
        println!(
            "(no --reference: relMSE estimated from the even/odd half-buffers; the estimate cannot see bias)"
        );
    }
}
