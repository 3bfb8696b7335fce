//! The stress suite (`scenes/stress/`, `illum stress`): one scene per numerically hard case, each
//! rendered for a fixed time on every trace path the device has, its non-finite samples counted
//! and its relMSE measured against a reference for that case: a closed form where one exists
//! ([`closed_form`]), otherwise a high-sample render by a different technique.

pub mod closed_form;
pub mod many_lights;

use crate::error::{Error, Result};
use crate::integrators::{Direct, DirectLighting, Technique};
use crate::render::{RenderSettings, Renderer};
use crate::scene::Scene;
use crate::trace::TraceMode;
use std::fmt::Write as _;
use std::path::Path;

/// A relative floor under the standard error of an image mean: float32 rounding of the film's
/// sums, which no amount of samples removes (zero-variance cases would otherwise read |z| = ∞).
pub const FLOAT_FLOOR: f64 = 1e-5;

/// How a case's reference image is made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reference {
    /// [`closed_form::image`].
    ClosedForm,
    /// A render by this technique (not the MIS under test) at many samples per pixel.
    Technique(Technique),
}

#[derive(Clone, Copy, Debug)]
pub struct Case {
    /// File stem in `scenes/stress/`.
    pub name: &'static str,
    pub reference: Reference,
}

/// Every case, in report order.
pub const CASES: &[Case] = &[
    closed("microfacet-alpha-1e-4"),
    closed("microfacet-alpha-1e-3"),
    by_light("microfacet-alpha-1"),
    by_light("anisotropic-100"),
    closed("grazing-diffuse"),
    by_light("grazing-glossy"),
    closed("sphere-light-tiny"),
    closed("sphere-light-touching"),
    closed("rect-light-huge-far"),
    closed("rect-light-huge-near"),
    closed("disk-light-huge-near"),
    closed("emitter-huge-near"),
    closed("far-from-origin"),
    closed("dome-hot-pixel"),
    closed("triangles-degenerate"),
    closed("lights-zero"),
    closed("sun-delta"),
    closed("sun-30deg"),
];

const fn closed(name: &'static str) -> Case {
    Case {
        name,
        reference: Reference::ClosedForm,
    }
}

const fn by_light(name: &'static str) -> Case {
    Case {
        name,
        reference: Reference::Technique(Technique::Light),
    }
}

impl Case {
    pub fn load(&self, dir: &Path) -> Result<Scene> {
        Ok(crate::scene::load(
            &dir.join(format!("{}.json", self.name)),
        )?)
    }

    /// The reference image at the scene's resolution.
    pub fn reference(
        &self,
        renderer: &Renderer,
        scene: &Scene,
        spp: u32,
    ) -> Result<ReferenceImage> {
        match self.reference {
            Reference::ClosedForm => {
                let image = closed_form::image(scene)
                    .map_err(|e| Error::Invalid(format!("{}: no closed form: {e}", self.name)))?;
                Ok(ReferenceImage {
                    image,
                    variance: None,
                    what: "closed form (f64)".into(),
                })
            }
            Reference::Technique(t) => {
                let settings = RenderSettings {
                    integrator: Direct(DirectLighting {
                        technique: t,
                        ..Default::default()
                    })
                    .into(),
                    spp,
                    seed: 0x5eed_f4ef,
                    ..Default::default()
                };
                let out = renderer.render(scene, &settings, &mut |_, _| {})?;
                if out.stats.non_finite_samples > 0 {
                    return Err(Error::Invalid(format!(
                        "{}: the reference render had {} non-finite samples",
                        self.name, out.stats.non_finite_samples
                    )));
                }
                Ok(ReferenceImage {
                    image: out.film.beauty,
                    variance: out.film.variance,
                    what: format!("`{}` sampling, {spp} spp", t.name()),
                })
            }
        }
    }
}

pub struct ReferenceImage {
    pub image: Vec<[f32; 3]>,
    /// Variance of each pixel's mean, for rendered references.
    pub variance: Option<Vec<[f32; 3]>>,
    pub what: String,
}

/// Mean luminance of an image and, given the variance of each pixel's mean, its standard error.
/// Channels are taken as fully correlated (exact for grey scenes, conservative otherwise).
pub fn mean_luminance(image: &[[f32; 3]], variance: Option<&[[f32; 3]]>) -> (f64, f64) {
    const W: [f64; 3] = [0.2126, 0.7152, 0.0722];
    let n = image.len().max(1) as f64;
    let lum =
        |p: &[f32; 3], f: fn(f64) -> f64| (0..3).map(|c| W[c] * f(f64::from(p[c]))).sum::<f64>();
    let mean = image.iter().map(|p| lum(p, |x| x)).sum::<f64>() / n;
    let var = variance.map_or(0.0, |v| {
        v.iter()
            .map(|p| lum(p, |x| x.max(0.0).sqrt()).powi(2))
            .sum::<f64>()
            / (n * n)
    });
    (mean, var.sqrt())
}

/// One row of the report: a case on one trace path.
#[derive(Clone, Debug)]
pub struct Row {
    pub case: &'static str,
    pub description: String,
    pub reference: String,
    pub trace: &'static str,
    pub spp: u32,
    pub seconds: f64,
    pub relmse: f64,
    pub non_finite_samples: u64,
    /// Image mean over the reference's mean (luminance).
    pub mean_ratio: f64,
    /// (image mean - reference mean) / its standard error (both renders' noise).
    pub z: f64,
}

pub struct StressOptions {
    /// Render time per case and trace path, seconds.
    pub seconds: f64,
    /// Image size (overrides the scenes' cameras).
    pub width: u32,
    pub height: u32,
    /// Samples per pixel of technique references.
    pub reference_spp: u32,
}

/// Runs every case on every trace path of the renderer's device; `log` hears of each row.
pub fn run(
    renderer: &Renderer,
    dir: &Path,
    o: &StressOptions,
    log: &mut dyn FnMut(&Row),
) -> Result<Vec<Row>> {
    let mut paths = vec![TraceMode::Bvh];
    if TraceMode::RayQuery.resolve(renderer.context()).is_ok() {
        paths.push(TraceMode::RayQuery);
    }
    let mut rows = Vec::new();
    for (index, case) in CASES.iter().enumerate() {
        let mut scene = case.load(dir)?;
        scene.camera.width = o.width;
        scene.camera.height = o.height;
        let r = case.reference(renderer, &scene, o.reference_spp)?;
        let (ref_mean, ref_se) = mean_luminance(&r.image, r.variance.as_deref());
        for &trace in &paths {
            let settings = RenderSettings {
                spp: 1 << 20,
                time: Some(o.seconds),
                // Independent random streams per case (cases share geometry).
                seed: index as u64 + 1,
                trace,
                reference: Some(r.image.clone()),
                ..Default::default()
            };
            let out = renderer.render(&scene, &settings, &mut |_, _| {})?;
            let err = out.passes.last().and_then(|p| p.error).unwrap_or_default();
            let (mean, se) = mean_luminance(&out.film.beauty, out.film.variance.as_deref());
            let row = Row {
                case: case.name,
                description: scene.description.clone().unwrap_or_default(),
                reference: r.what.clone(),
                trace: out.stats.trace,
                spp: out.stats.spp,
                seconds: out.stats.render_seconds,
                relmse: err.relmse,
                non_finite_samples: out.stats.non_finite_samples,
                mean_ratio: mean / ref_mean,
                z: (mean - ref_mean) / se.hypot(ref_se).hypot(FLOAT_FLOOR * ref_mean),
            };
            log(&row);
            rows.push(row);
        }
    }
    Ok(rows)
}

/// The report as Markdown (docs/stress.md).
pub fn markdown(rows: &[Row], o: &StressOptions, device: &str, command: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Stress report\n");
    let _ = writeln!(
        s,
        "Generated by `{command}` on {device}: each case of [`scenes/stress/`](../scenes/stress) \
         rendered for {} s at {}x{} with the default integrator (MIS) on every trace path of the \
         device. relMSE (ε = 0.01) is against the case's reference: a closed form evaluated in \
         float64 on the host (`src/stress/closed_form.rs`), or a render by a different technique \
         at {} spp. Each case has its own seed. Non-finite samples are camera samples whose value was NaN or infinite (counted \
         before accumulation, then replaced by 0). Mean ratio is the image's mean luminance over \
         the reference's, and z that difference over its standard error (both images' noise, and a 1e-5 relative floor \
         for float32 sums; |z| > 4 flags a bias).\n",
        o.seconds, o.width, o.height, o.reference_spp
    );
    let _ = writeln!(
        s,
        "| case | what is extreme | reference | trace | spp | relMSE | non-finite samples | mean ratio | z |"
    );
    let _ = writeln!(s, "|---|---|---|---|---:|---:|---:|---:|---:|");
    for r in rows {
        let _ = writeln!(
            s,
            "| `{}` | {} | {} | {} | {} | {:.2e} | {} | {:.5} | {:+.1} |",
            r.case,
            r.description.replace('|', "\\|"),
            r.reference,
            r.trace,
            r.spp,
            r.relmse,
            r.non_finite_samples,
            r.mean_ratio,
            r.z
        );
    }
    s
}
