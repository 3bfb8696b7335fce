//! `illum bench trace`: trace throughput, build time and memory of both trace paths.
//! `illum bench prepared`: what rendering a prepared scene again saves over a fresh render.
//! `illum bench lights`: light selection (tree, the former linear scan, a loop over every light)
//! with N sphere lights (src/cli/bench_lights.rs).

use crate::trace::TraceMode;
use crate::trace::bench;
use crate::vk::{Context, ContextOptions};
use anyhow::Result;
use clap::Subcommand;

#[derive(Subcommand)]
pub enum BenchCommand {
    /// Ray throughput, build time and memory of the trace paths (ray queries, compute BVH) on
    /// procedurally generated meshes.
    Trace(BenchTraceArgs),
    /// Wall time of a fresh render against a render of the same scene already prepared (uploaded
    /// and built), and the bytes each uploads.
    Prepared(BenchPreparedArgs),
    /// Camera samples per second and equal-time relMSE of the light selections with N sphere
    /// lights of equal total power (src/stress/many_lights.rs).
    Lights(super::bench_lights::BenchLightsArgs),
}

#[derive(clap::Args)]
pub struct BenchPreparedArgs {
    #[command(flatten)]
    pub scene: super::SceneArgs,
    /// Samples per pixel of each render.
    #[arg(long, default_value_t = 1)]
    pub spp: u32,
    /// Renders of each kind; the best time is printed.
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Trace path: auto, rayquery or bvh.
    #[arg(long, default_value = "auto")]
    pub trace: TraceMode,
    /// Device index or a substring of its name (see `illum devices`).
    #[arg(long)]
    pub device: Option<String>,
}

#[derive(clap::Args)]
pub struct BenchTraceArgs {
    /// Triangle counts of the procedural meshes, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "100000,1000000")]
    pub triangles: Vec<usize>,
    /// Rays per measurement.
    #[arg(long, default_value_t = 1 << 18)]
    pub rays: usize,
    /// Paths to measure: both, rayquery or bvh.
    #[arg(long, default_value = "both")]
    pub trace: String,
    /// Measurements of each figure; the best one is printed.
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Device index or a substring of its name (see `illum devices`).
    #[arg(long)]
    pub device: Option<String>,
    /// Enable the Vulkan validation layers.
    #[arg(long)]
    pub validate: bool,
}

pub fn run(command: &BenchCommand) -> Result<()> {
    match command {
        BenchCommand::Trace(a) => trace(a),
        BenchCommand::Prepared(a) => prepared(a),
        BenchCommand::Lights(a) => super::bench_lights::run(a),
    }
}

fn prepared(a: &BenchPreparedArgs) -> Result<()> {
    use crate::render::{RenderSettings, Renderer};
    use std::time::Instant;
    let scene = a.scene.load()?;
    let ctx = Context::new(&ContextOptions {
        device: a.device.clone(),
        validation: false,
        ..Default::default()
    })?;
    let r = Renderer::new(ctx.clone());
    let settings = RenderSettings {
        spp: a.spp,
        trace: a.trace,
        ..Default::default()
    };
    // Warm the driver's caches (kernel compilation) and the loop probe first.
    r.render(&scene, &settings, &mut |_, _| {})?;
    let measure = |f: &mut dyn FnMut() -> crate::Result<()>| -> Result<(f64, u64)> {
        let mut best = (f64::INFINITY, 0);
        for _ in 0..a.repeat.max(1) {
            let (_, b0) = ctx.upload_counts();
            let t = Instant::now();
            f()?;
            let dt = t.elapsed().as_secs_f64();
            let (_, b1) = ctx.upload_counts();
            if dt < best.0 {
                best = (dt, b1 - b0);
            }
        }
        Ok(best)
    };
    let fresh = measure(&mut || r.render(&scene, &settings, &mut |_, _| {}).map(|_| ()))?;
    let t = Instant::now();
    let prepared = r.prepare(&scene, a.trace)?;
    let prepare_seconds = t.elapsed().as_secs_f64();
    let again = measure(&mut || {
        r.render_prepared(&prepared, &scene.camera, &settings, &[0], &mut |_, _| {})
            .map(|_| ())
    })?;
    println!(
        "{} {}x{} at {} spp on {} via {}: fresh render {:.3} s ({} bytes uploaded); prepare {:.3} s; \
         render of the prepared scene {:.3} s ({} bytes uploaded): {:.3} s saved per render",
        a.scene.name(),
        scene.camera.width,
        scene.camera.height,
        a.spp,
        ctx.info().name,
        prepared.trace_name(),
        fresh.0,
        fresh.1,
        prepare_seconds,
        again.0,
        again.1,
        fresh.0 - again.0
    );
    updates(&ctx, prepared, scene, a.repeat)
}

/// Best wall time of `PreparedScene::update` for each kind of edit the scene allows, with the
/// bytes written and the levels built. Edits alternate between two values so that each changes.
fn updates(
    ctx: &Context,
    mut prepared: crate::render::PreparedScene,
    scene: crate::scene::Scene,
    repeat: usize,
) -> Result<()> {
    type Edit = fn(&mut crate::scene::Scene, bool);
    let mut edits: Vec<(&str, Edit)> = vec![("camera move", |s, odd| {
        s.camera.position.x += if odd { 0.01 } else { -0.01 };
    })];
    if !scene.materials.is_empty() {
        edits.push(("material edit", |s, odd| {
            let d = &mut s.materials[0].diffuse.x;
            *d += if *d > 0.5 { -0.25 } else { 0.25 };
            let _ = odd;
        }));
    }
    if scene.lights.iter().any(|l| !l.emits_nothing()) {
        edits.push(("light edit", |s, odd| {
            let l = s.lights.iter_mut().find(|l| !l.emits_nothing()).unwrap();
            l.intensity *= if odd { 1.25 } else { 0.8 };
        }));
    }
    if !scene.instances.is_empty() {
        edits.push(("instance transform", |s, odd| {
            let step = glam::DVec3::new(if odd { 0.01 } else { -0.01 }, 0.0, 0.0);
            for i in &mut s.instances {
                i.transform = glam::DMat4::from_translation(step) * i.transform;
            }
        }));
    }
    for (name, edit) in edits {
        let mut s = scene.clone();
        let mut best = (f64::INFINITY, 0, (0, 0));
        for k in 0..repeat.max(1) * 2 {
            edit(&mut s, k % 2 == 1);
            let ((_, b0), l0) = (ctx.upload_counts(), ctx.build_counts());
            let u = prepared.update(ctx, &s)?;
            let ((_, b1), l1) = (ctx.upload_counts(), ctx.build_counts());
            if u.seconds < best.0 {
                best = (u.seconds, b1 - b0, (l1.0 - l0.0, l1.1 - l0.1));
            }
        }
        println!(
            "update, {name}: {:.3} ms, {} bytes written, {} bottom and {} top levels built",
            best.0 * 1e3,
            best.1,
            best.2.0,
            best.2.1
        );
    }
    Ok(())
}

fn trace(a: &BenchTraceArgs) -> Result<()> {
    let paths = match a.trace.as_str() {
        "both" => vec![TraceMode::RayQuery, TraceMode::Bvh],
        other => vec![other.parse::<TraceMode>().map_err(anyhow::Error::msg)?],
    };
    let ctx = Context::new(&ContextOptions {
        device: a.device.clone(),
        validation: a.validate,
        ..Default::default()
    })?;
    if paths.contains(&TraceMode::RayQuery) && !ctx.ray_query() {
        crate::note!(
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
    // A CPU device's threads are this process's: rays per CPU-second. A GPU's: rays per second
    // of the dispatches' own device time, without the submissions' round trips.
    let cpu_device = ctx.info().kind == "CPU";
    let rate = |r: bench::Rate| match (cpu_device, r.cpu, r.device) {
        (true, Some(c), _) => format!("{:.3} ({:.3})", r.wall, c),
        (false, _, Some(d)) => format!("{:.3} [{:.3}]", r.wall, d),
        _ => format!("{:.3}", r.wall),
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
        "Mrays per second of wall time {}; bounce rays: cosine-distributed from the first hits",
        if cpu_device {
            "(and per CPU-second of this process, which other load on the machine disturbs less)"
        } else {
            "[and per second of the dispatches' device time (timestamps), without submissions]"
        }
    );
    super::check_validation(&ctx)
}
