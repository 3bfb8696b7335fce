//! Comparisons: several integrators, direct-lighting techniques or sample allocations rendered
//! on one scene for the same time, with their error table, error-against-time curves and an
//! image strip with error heat-maps. `illum compare` and Python's `illum.compare` both run this;
//! they differ only in how they show progress and where the images go.

use crate::error::{Error, Result};
use crate::integrators::Technique;
use crate::render::{Integrator, Params, PassReport, RenderOutput, RenderSettings};
use crate::report::{Panel, Series};
use crate::trace::TraceMode;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

/// One sample allocation: light samples, BRDF samples per lobe and, when set, diffuse MIS.
#[derive(Clone, Debug)]
pub struct Samples {
    pub light: u32,
    pub brdf: u32,
    pub diffuse_mis: Option<bool>,
    /// Its name in run names: `4-2`, `1-1-dmis`.
    pub name: String,
}

/// `L/B`, `L/B/dmis` or `L/B/nodmis` (L, B in 1..=64).
pub fn parse_samples(s: &str) -> Result<Samples, String> {
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

/// What to compare: every integrator × sample allocation × technique named.
pub struct Spec<'a> {
    /// None: brdf, light and mis when neither integrators nor samples are named, else mis.
    pub techniques: Option<Vec<Technique>>,
    /// Integrator names or [`ALIASES`]; empty: `default_integrator` alone.
    pub integrators: Vec<String>,
    /// Empty: the allocation the integrator's parameters name.
    pub samples: Vec<Samples>,
    pub default_integrator: String,
    /// The parameters of an integrator before the comparison's own (the scene's, then the
    /// caller's options).
    pub params: &'a dyn Fn(&str) -> Result<Params, String>,
    /// How the caller spells an argument in messages (`--techniques`, `techniques=`).
    pub arg: fn(&str) -> String,
}

/// One rendering of the comparison: its name (unique) and integrator.
pub struct Run {
    pub name: String,
    pub integrator: Arc<dyn Integrator>,
}

/// A name `integrators` takes besides the integrators' own: (name, integrator, parameters).
pub type Alias = (
    &'static str,
    &'static str,
    &'static [(&'static str, &'static str)],
);

pub const ALIASES: &[Alias] = &[
    ("full-nocache", "full", &[("radiosity_cache", "off")]),
    ("full-nocaustics", "full", &[("caustics", "off")]),
];

fn alias_names() -> String {
    let n: Vec<&str> = ALIASES.iter().map(|a| a.0).collect();
    n.join(", ")
}

impl Spec<'_> {
    /// The runs, in order (integrator, then allocation, then technique), each with a unique name.
    pub fn runs(&self) -> Result<Vec<Run>> {
        let invalid = |m: String| Error::Invalid(m);
        let techniques = match &self.techniques {
            Some(t) => t.clone(),
            None if self.integrators.is_empty() && self.samples.is_empty() => {
                vec![Technique::Brdf, Technique::Light, Technique::Mis]
            }
            None => vec![Technique::Mis],
        };
        if techniques.is_empty() {
            return Err(invalid(format!(
                "{}: name at least one of brdf, light, mis",
                (self.arg)("techniques")
            )));
        }
        let integrators: Vec<Option<&str>> = if self.integrators.is_empty() {
            vec![None]
        } else {
            self.integrators.iter().map(|s| Some(s.as_str())).collect()
        };
        let samples: Vec<Option<&Samples>> = if self.samples.is_empty() {
            vec![None]
        } else {
            self.samples.iter().map(Some).collect()
        };
        let mut runs: Vec<Run> = Vec::new();
        for (integrator, sa) in integrators
            .iter()
            .flat_map(|i| samples.iter().map(move |s| (i, s)))
        {
            for &t in &techniques {
                let run = self.run(*integrator, *sa, t, techniques.len())?;
                if runs.iter().any(|r| r.name == run.name) {
                    return Err(invalid(format!(
                        "{}, {}, {}: {} is named twice (each renders once, under its name)",
                        (self.arg)("techniques"),
                        (self.arg)("integrators"),
                        (self.arg)("samples"),
                        run.name
                    )));
                }
                runs.push(run);
            }
        }
        Ok(runs)
    }

    fn run(
        &self,
        integrator: Option<&str>,
        sa: Option<&Samples>,
        t: Technique,
        techniques: usize,
    ) -> Result<Run> {
        let (kind, extra): (&str, &[(&str, &str)]) = match integrator {
            Some(spec) => match ALIASES.iter().find(|(n, ..)| *n == spec) {
                Some((_, kind, extra)) => (kind, extra),
                None => (spec, &[]),
            },
            None => (&self.default_integrator, &[]),
        };
        let mut p = (self.params)(kind).map_err(Error::Invalid)?;
        p.set("technique", t.name(), (self.arg)("techniques"));
        if let Some(sa) = sa {
            let origin = (self.arg)("samples");
            p.set("light_samples", sa.light.to_string(), &origin);
            p.set("brdf_samples", sa.brdf.to_string(), &origin);
            if let Some(d) = sa.diffuse_mis {
                p.set("diffuse_mis", if d { "on" } else { "off" }, &origin);
            }
        }
        for (k, v) in extra {
            let origin = format!("{} {}", (self.arg)("integrators"), integrator.unwrap_or(""));
            p.set(k, *v, origin);
        }
        let it = crate::integrators::create(kind, &p).map_err(|e| {
            Error::Invalid(match integrator {
                Some(_) => format!("{e} (or one of the aliases: {})", alias_names()),
                None => e,
            })
        })?;
        let mut name = match (integrator, techniques) {
            (None, _) => t.name().to_string(),
            (Some(i), 1) => i.to_string(),
            (Some(i), _) => format!("{i}-{}", t.name()),
        };
        if let Some(sa) = sa {
            name = if integrator.is_none() && techniques == 1 {
                sa.name.clone()
            } else {
                format!("{name}-{}", sa.name)
            };
        }
        Ok(Run {
            name,
            integrator: it,
        })
    }

    /// What the runs vary, for the table's first column.
    pub fn kind(&self) -> &'static str {
        match (self.integrators.is_empty(), self.samples.is_empty()) {
            (true, true) => "technique",
            (false, true) => "integrator",
            _ => "run",
        }
    }
}

/// The budget every run renders under.
#[derive(Clone)]
pub struct Budget {
    pub time: f64,
    pub seed: u64,
    pub trace: TraceMode,
    pub reference: Option<Vec<[f32; 3]>>,
    pub cancel: Option<Arc<AtomicBool>>,
}

impl Budget {
    /// The settings of `run`: `time` seconds without a sample cap, every pass evaluated.
    pub fn settings(&self, run: &Run) -> RenderSettings {
        RenderSettings {
            integrator: run.integrator.clone(),
            spp: 1 << 20,
            time: Some(self.time),
            seed: self.seed,
            trace: self.trace,
            reference: self.reference.clone(),
            evaluate_passes: true,
            cancel: self.cancel.clone(),
            ..Default::default()
        }
    }
}

/// The rendered runs, by name.
pub struct Comparison {
    pub runs: Vec<(String, RenderOutput)>,
    /// Whether the errors are measured against a reference (else estimated from half-buffers).
    pub measured: bool,
    pub time: f64,
}

/// A line of the comparison's table.
pub struct Row {
    pub name: String,
    pub spp: u32,
    pub seconds: f64,
    /// Against the reference, else the half-buffer estimate (NaN when unknown).
    pub relmse: f64,
    /// 1 / (relMSE × seconds).
    pub efficiency: f64,
}

/// A pass's relMSE: against the reference when there is one, else the half-buffer estimate.
pub fn error_of(p: &PassReport, measured: bool) -> Option<f64> {
    if measured {
        p.error.map(|e| e.relmse)
    } else {
        p.estimated_relmse
    }
}

impl Comparison {
    pub fn rows(&self) -> Vec<Row> {
        self.runs
            .iter()
            .map(|(name, out)| {
                let last = out.passes.last().cloned().unwrap_or_default();
                let relmse = error_of(&last, self.measured).unwrap_or(f64::NAN);
                Row {
                    name: name.clone(),
                    spp: last.spp,
                    seconds: last.wall_seconds,
                    relmse,
                    efficiency: 1.0 / (relmse * last.wall_seconds),
                }
            })
            .collect()
    }

    /// Each run's error against wall time, one point per pass.
    pub fn series(&self) -> Vec<Series> {
        self.runs
            .iter()
            .map(|(name, out)| Series {
                name: name.clone(),
                points: out
                    .passes
                    .iter()
                    .filter_map(|p| Some((p.wall_seconds, error_of(p, self.measured)?)))
                    .collect(),
            })
            .collect()
    }

    /// The error-against-time plot (PNG).
    pub fn write_plot(&self, path: &Path) -> Result<()> {
        let y = if self.measured {
            "relMSE"
        } else {
            "estimated relMSE (half-buffers)"
        };
        crate::report::plot_error(path, &format!("{:.1} s each", self.time), y, &self.series())
    }

    /// The strip of the runs' images, each with its error map (PNG).
    pub fn write_strip(&self, path: &Path, reference: Option<&[[f32; 3]]>) -> Result<()> {
        let panels: Vec<Panel> = self
            .runs
            .iter()
            .map(|(name, out)| Panel {
                label: format!(
                    "{} {}spp {:.1e}",
                    name,
                    out.stats.spp,
                    out.passes
                        .last()
                        .and_then(|p| error_of(p, self.measured))
                        .unwrap_or(f64::NAN)
                ),
                film: &out.film,
                error: match reference {
                    Some(r) => crate::report::relative_error_map(&out.film.beauty, r),
                    None => variance_map(out),
                },
            })
            .collect();
        crate::report::image_strip(path, &panels)
    }
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
