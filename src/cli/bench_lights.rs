//! `illum bench lights`: with N sphere lights of equal total power (src/stress/many_lights.rs),
//! camera samples per second and relMSE at equal render time of each light selection: the light
//! tree, the linear CDF scan it replaced, and a loop over every light. The reference of each N is
//! a tree render of `--reference-factor` times the time (its own error is in the figures at about
//! 1/factor of a tree render's).

use crate::integrators::{Direct, DirectLighting, LightSelection};
use crate::render::{RenderSettings, Renderer};
use crate::stress::many_lights::{ManyLights, scene_json};
use crate::trace::TraceMode;
use crate::vk::{Context, ContextOptions};
use anyhow::Result;
use std::path::Path;

#[derive(clap::Args)]
pub struct BenchLightsArgs {
    /// Light counts, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "8,64,1000,100000")]
    pub lights: Vec<usize>,
    /// Selections to measure, comma-separated: tree, scan, loop.
    #[arg(long, value_delimiter = ',', default_value = "tree,scan")]
    pub selection: Vec<LightSelection>,
    /// Render seconds of each measurement (at least one sample per pixel is rendered).
    #[arg(long, default_value_t = 2.0)]
    pub seconds: f64,
    /// The reference renders this many times longer.
    #[arg(long, default_value_t = 8.0)]
    pub reference_factor: f64,
    #[arg(long, default_value_t = 64)]
    pub width: u32,
    #[arg(long, default_value_t = 48)]
    pub height: u32,
    /// Trace path: auto, rayquery or bvh.
    #[arg(long, default_value = "auto")]
    pub trace: TraceMode,
    /// Device index or a substring of its name (see `illum devices`).
    #[arg(long)]
    pub device: Option<String>,
}

pub fn run(a: &BenchLightsArgs) -> Result<()> {
    if !(a.seconds > 0.0 && a.reference_factor >= 1.0) {
        anyhow::bail!("--seconds must be > 0 and --reference-factor >= 1");
    }
    if let Some(n) = a.lights.iter().find(|&&n| n == 0) {
        anyhow::bail!("--lights: {n} lights: at least 1");
    }
    let ctx = Context::new(&ContextOptions {
        device: a.device.clone(),
        validation: false,
        ..Default::default()
    })?;
    let r = Renderer::new(ctx.clone());
    println!(
        "device: {} ({}), {}x{}, {} s per measurement, reference {}x longer (tree)",
        ctx.info().name,
        ctx.info().driver,
        a.width,
        a.height,
        a.seconds,
        a.reference_factor
    );
    println!(
        "{:>7} {:>6} | {:>6} {:>14} {:>12} | {:>9} | {:>10}",
        "lights", "select", "spp", "M samples/s", "relMSE", "x tree", "mean lum."
    );
    for &n in &a.lights {
        let json = scene_json(n, ManyLights::Spheres, a.width, a.height);
        let scene = crate::scene::from_json_str(&json, "bench lights", Path::new("."))?;
        let prepared = r.prepare(&scene, a.trace)?;
        let render = |sel: LightSelection, seconds: f64, seed: u64| {
            let settings = RenderSettings {
                spp: 1 << 20,
                time: Some(seconds),
                seed,
                trace: a.trace,
                integrator: Direct(DirectLighting {
                    light_selection: sel,
                    ..Default::default()
                })
                .into(),
                ..Default::default()
            };
            r.render_prepared(&prepared, &scene.camera, &settings, &[seed], &mut |_, _| {})
                .map(|mut v| v.remove(0))
        };
        let reference = render(LightSelection::Tree, a.seconds * a.reference_factor, 99)?;
        let mut tree_relmse = None;
        for &sel in &a.selection {
            let out = render(sel, a.seconds, 1)?;
            let samples = f64::from(a.width * a.height) * f64::from(out.stats.spp);
            let rate = samples / out.stats.render_seconds / 1e6;
            let relmse = crate::metrics::compare(&out.film.beauty, &reference.film.beauty).relmse;
            if sel == LightSelection::Tree {
                tree_relmse = Some(relmse);
            }
            let ratio = tree_relmse.map_or("".into(), |t| format!("{:.2}", relmse / t));
            println!(
                "{n:>7} {:>6} | {:>6} {rate:>14.4} {relmse:>12.4e} | {ratio:>9} | {:>10.5}",
                sel.name(),
                out.stats.spp,
                mean_luminance(&out.film.beauty),
            );
        }
        println!(
            "{n:>7} {:>6} | {:>6} {:>14} {:>12} | {:>9} | {:>10.5}",
            "ref.",
            reference.stats.spp,
            "",
            "",
            "",
            mean_luminance(&reference.film.beauty)
        );
    }
    Ok(())
}

fn mean_luminance(image: &[[f32; 3]]) -> f64 {
    let sum: f64 = image
        .iter()
        .map(|p| crate::gpu_scene::dome::luminance(glam::Vec3::from(*p).as_dvec3()))
        .sum();
    sum / image.len().max(1) as f64
}
