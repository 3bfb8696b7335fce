//! `illum compare`: several integrators or direct-lighting techniques rendered for the same time,
//! with their error table, error-against-time curves and an image strip with error heat-maps.

use super::render::{announce_compiles, progress_bar};
use super::{IntegratorArgs, Interrupted, SceneArgs, check_outputs, image_metadata, signal};
use crate::integrators::Technique;
use crate::output::write_exr;
use crate::render::{Integrator, PassReport, RenderOutput, RenderSettings, Renderer};
use crate::trace::TraceMode;
use crate::vk::{Context, ContextOptions};
use anyhow::{Result, bail};
use std::path::PathBuf;
use std::sync::Arc;
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

/// One sample allocation of `--samples`.
#[derive(Clone, Debug)]
pub struct Samples {
    light: u32,
    brdf: u32,
    diffuse_mis: Option<bool>,
    name: String,
}

fn parse_samples(s: &str) -> Result<Samples, String> {
    let bad = || format!("{s:?}: expected L/B, L/B/dmis or L/B/nodmis (L, B in 1..=64)");
    let parts: Vec<&str> = s.split('/').collect();
    let count = |p: &str| p.parse::<u32>().ok().filter(|n| (1..=64).contains(n));
    let (Some(light), Some(brdf)) = (
        parts.first().and_then(|p| count(p)),
        parts.get(1).and_then(|p| count(p)),
    ) else {
        return Err(bad());
    };
    let diffuse_mis = match parts.get(2..) {
        Some([]) => None,
        Some(["dmis"]) => Some(true),
        Some(["nodmis"]) => Some(false),
        _ => return Err(bad()),
    };
    Ok(Samples {
        light,
        brdf,
        diffuse_mis,
        name: parts.join("-"),
    })
}

/// One rendering of the comparison: its name and integrator.
struct Run {
    name: String,
    integrator: Arc<dyn Integrator>,
}

/// A name `--integrators` takes besides the integrators' own: (name, integrator, parameters).
type Alias = (
    &'static str,
    &'static str,
    &'static [(&'static str, &'static str)],
);

const ALIASES: &[Alias] = &[
    ("full-nocache", "full", &[("radiosity_cache", "off")]),
    ("full-nocaustics", "full", &[("caustics", "off")]),
];

fn alias_names() -> String {
    let n: Vec<&str> = ALIASES.iter().map(|a| a.0).collect();
    n.join(", ")
}

fn runs(a: &CompareArgs, scene: &crate::scene::Scene) -> Result<Vec<Run>> {
    let techniques = match &a.techniques {
        Some(t) => t.clone(),
        None if a.integrators.is_empty() && a.samples.is_empty() => {
            vec![Technique::Brdf, Technique::Light, Technique::Mis]
        }
        None => vec![Technique::Mis],
    };
    if techniques.is_empty() {
        bail!("--techniques: name at least one of brdf, light, mis");
    }
    let mut runs = Vec::new();
    let integrators: Vec<Option<&str>> = if a.integrators.is_empty() {
        vec![None]
    } else {
        a.integrators.iter().map(|s| Some(s.as_str())).collect()
    };
    let samples: Vec<Option<&Samples>> = if a.samples.is_empty() {
        vec![None]
    } else {
        a.samples.iter().map(Some).collect()
    };
    for (integrator, sa) in integrators
        .iter()
        .flat_map(|i| samples.iter().map(move |s| (i, s)))
    {
        for &t in &techniques {
            let (kind, extra): (String, &[(&str, &str)]) = match integrator {
                Some(spec) => match ALIASES.iter().find(|(n, ..)| n == spec) {
                    Some((_, kind, extra)) => (kind.to_string(), extra),
                    None => (spec.to_string(), &[]),
                },
                None => (a.integrator.name(scene), &[]),
            };
            let mut p = a.integrator.params(&kind, scene)?;
            p.set("technique", t.name(), "--techniques");
            if let Some(sa) = sa {
                p.set("light_samples", sa.light.to_string(), "--samples");
                p.set("brdf_samples", sa.brdf.to_string(), "--samples");
                if let Some(d) = sa.diffuse_mis {
                    p.set("diffuse_mis", if d { "on" } else { "off" }, "--samples");
                }
            }
            for (k, v) in extra {
                p.set(k, *v, format!("--integrators {}", integrator.unwrap_or("")));
            }
            let it = crate::integrators::create(&kind, &p).map_err(|e| {
                anyhow::anyhow!(
                    "{e}{}",
                    if integrator.is_some() {
                        format!(" (or one of the aliases: {})", alias_names())
                    } else {
                        String::new()
                    }
                )
            })?;
            let mut name = match (integrator, techniques.len()) {
                (None, _) => t.name().to_string(),
                (Some(i), 1) => i.to_string(),
                (Some(i), _) => format!("{i}-{}", t.name()),
            };
            if let Some(sa) = sa {
                name = if integrator.is_none() && techniques.len() == 1 {
                    sa.name.clone()
                } else {
                    format!("{name}-{}", sa.name)
                };
            }
            if runs.iter().any(|r: &Run| r.name == name) {
                bail!(
                    "--techniques, --integrators, --samples: {name} is named twice (each renders once, to \
                     {}-{name}.exr)",
                    a.output.display()
                );
            }
            runs.push(Run {
                name,
                integrator: it,
            });
        }
    }
    Ok(runs)
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

pub fn run(a: &CompareArgs) -> Result<()> {
    let scene = a.scene.load()?;
    let runs = runs(a, &scene)?;
    let files = Outputs::new(a, &runs)?;
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
    let mut rows: Vec<(String, RenderOutput)> = Vec::new();
    for (run, exr) in runs.iter().zip(&files.exrs) {
        let settings = RenderSettings {
            integrator: run.integrator.clone(),
            spp: 1 << 20,
            time: Some(a.time),
            seed: a.seed,
            trace: a.trace,
            reference: reference.clone(),
            evaluate_passes: true,
            cancel: Some(cancel.clone()),
            ..Default::default()
        };
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
        rows.push((run.name.clone(), out));
    }
    let measured = reference.is_some();
    let series = print_table(a, &rows, measured);
    crate::report::plot_error(
        &files.plot,
        &format!("{:.1} s each", a.time),
        if measured {
            "relMSE"
        } else {
            "estimated relMSE (half-buffers)"
        },
        &series,
    )?;
    write_strip(&files.strip, &rows, reference.as_deref())?;
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
    let setup_done = announce_compiles(ctx, &bar, a.quiet);
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

/// A pass's relMSE: against the reference when there is one, else the half-buffer estimate.
fn error_of(p: &PassReport, measured: bool) -> Option<f64> {
    if measured {
        p.error.map(|e| e.relmse)
    } else {
        p.estimated_relmse
    }
}

/// Prints the table of runs and returns their error-against-time curves.
fn print_table(
    a: &CompareArgs,
    rows: &[(String, RenderOutput)],
    measured: bool,
) -> Vec<crate::report::Series> {
    println!(
        "{:<14} {:>8} {:>10} {:>14} {:>14}",
        match (a.integrators.is_empty(), a.samples.is_empty()) {
            (true, true) => "technique",
            (false, true) => "integrator",
            _ => "run",
        },
        "spp",
        "seconds",
        if measured { "relMSE" } else { "est. relMSE" },
        "efficiency"
    );
    let mut series = Vec::new();
    for (t, out) in rows {
        let last = out.passes.last().cloned().unwrap_or_default();
        let err = error_of(&last, measured).unwrap_or(f64::NAN);
        println!(
            "{:<14} {:>8} {:>10.3} {:>14.4e} {:>14.4e}",
            t,
            last.spp,
            last.wall_seconds,
            err,
            1.0 / (err * last.wall_seconds)
        );
        series.push(crate::report::Series {
            name: t.clone(),
            points: out
                .passes
                .iter()
                .filter_map(|p| Some((p.wall_seconds, error_of(p, measured)?)))
                .collect(),
        });
    }
    if !measured {
        println!(
            "(no --reference: relMSE estimated from the even/odd half-buffers; the estimate cannot see bias)"
        );
    }
    series
}

/// The strip of the runs' images, each with its error map.
fn write_strip(
    path: &std::path::Path,
    rows: &[(String, RenderOutput)],
    reference: Option<&[[f32; 3]]>,
) -> Result<()> {
    let measured = reference.is_some();
    let maps: Vec<Vec<f64>> = rows
        .iter()
        .map(|(_, out)| match reference {
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
                t,
                out.stats.spp,
                out.passes
                    .last()
                    .and_then(|p| error_of(p, measured))
                    .unwrap_or(f64::NAN)
            ),
            film: &out.film,
            error,
        })
        .collect();
    crate::report::image_strip(path, &panels)?;
    Ok(())
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

#[cfg(test)]
mod tests {
    use super::parse_samples;

    #[test]
    fn samples_lists_parse_and_bad_ones_are_named() {
        let s = parse_samples("4/2").unwrap();
        assert_eq!(
            (s.light, s.brdf, s.diffuse_mis, s.name.as_str()),
            (4, 2, None, "4-2")
        );
        let s = parse_samples("1/1/dmis").unwrap();
        assert_eq!((s.light, s.brdf, s.diffuse_mis), (1, 1, Some(true)));
        assert_eq!(
            parse_samples("8/3/nodmis").unwrap().diffuse_mis,
            Some(false)
        );
        for bad in ["", "4", "0/1", "65/1", "4/2/x", "4/2/dmis/1", "a/b"] {
            let e = parse_samples(bad).unwrap_err();
            assert!(e.contains(&format!("{bad:?}")), "{bad}: {e}");
        }
    }
}
