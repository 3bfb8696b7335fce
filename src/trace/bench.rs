//! `illum bench trace`: ray throughput of the trace paths on procedural meshes, with the build
//! time and memory of each structure. Also the procedural meshes themselves, which the tests use.

use crate::error::Result;
use crate::gpu_scene::GpuScene;
use crate::layout::*;
use crate::scene::{Camera, Material, Mesh, MeshInstance, Scene};
use crate::trace::query::{HitRecord, QueryKernel, Ray};
use crate::trace::{BuildStats, TraceMode, TraceStructure};
use crate::vk::Context;
use glam::{DMat4, DVec3, Vec3};
use std::time::Instant;

/// A bumpy sphere of radius about 1 around the origin with about `triangles` triangles (a
/// latitude-longitude grid displaced by sums of sines, so that it shadows itself).
pub fn displaced_sphere(triangles: usize) -> Mesh {
    let rows = ((triangles as f64 / 4.0).sqrt().round() as usize).max(2);
    let cols = 2 * rows;
    let mut positions = Vec::with_capacity((rows + 1) * cols);
    let mut normals = Vec::with_capacity((rows + 1) * cols);
    for i in 0..=rows {
        let theta = std::f64::consts::PI * i as f64 / rows as f64;
        for j in 0..cols {
            let phi = std::f64::consts::TAU * j as f64 / cols as f64;
            let r = 1.0
                + 0.12 * (5.0 * theta).sin() * (7.0 * phi).sin()
                + 0.06 * (17.0 * theta + 1.0).sin() * (13.0 * phi).sin()
                + 0.03 * (41.0 * theta).sin() * (37.0 * phi + 2.0).sin();
            let n = DVec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            positions.push((n * r).as_vec3());
            normals.push(n.as_vec3());
        }
    }
    let mut indices = Vec::with_capacity(rows * cols * 6);
    for i in 0..rows {
        for j in 0..cols {
            let a = (i * cols + j) as u32;
            let b = (i * cols + (j + 1) % cols) as u32;
            let c = a + cols as u32;
            let d = b + cols as u32;
            indices.extend_from_slice(&[a, c, b, b, c, d]);
        }
    }
    Mesh {
        name: format!("displaced sphere ({} triangles)", indices.len() / 3),
        positions,
        normals: Some(normals),
        tangents: None,
        uvs: None,
        indices,
        material: 0,
    }
}

/// A scene of one mesh seen by a camera at `eye` looking at the origin.
pub fn mesh_scene(mesh: Mesh, eye: DVec3, size: u32) -> Scene {
    Scene {
        camera: Camera {
            position: eye,
            look_at: DVec3::ZERO,
            up: DVec3::Y,
            fov_y_deg: 40.0,
            width: size,
            height: size,
        },
        materials: vec![Material::lambert("grey", Vec3::splat(0.5))],
        textures: Vec::new(),
        meshes: vec![mesh],
        instances: vec![MeshInstance {
            mesh: 0,
            transform: DMat4::IDENTITY,
            name: "mesh".into(),
        }],
        shapes: Vec::new(),
        lights: Vec::new(),
        description: None,
        integrator: Default::default(),
        warnings: Vec::new(),
        source: None,
        inputs: Vec::new(),
    }
}

/// Camera rays of `scene` (render space: the camera at the origin), one per pixel of a
/// `size`² image, in 8x8 tiles like the primary kernel's workgroups.
pub fn camera_rays(gpu: &GpuScene, size: u32) -> Vec<Ray> {
    let f = &gpu.frame;
    let v = |a: [f32; 4]| Vec3::new(a[0], a[1], a[2]);
    let (fwd, right, up) = (v(f.cam_forward), v(f.cam_right), v(f.cam_up));
    let mut rays = Vec::with_capacity((size * size) as usize);
    for ty in (0..size).step_by(8) {
        for tx in (0..size).step_by(8) {
            for y in ty..(ty + 8).min(size) {
                for x in tx..(tx + 8).min(size) {
                    let ndc_x = 2.0 * (x as f32 + 0.5) / size as f32 - 1.0;
                    let ndc_y = 2.0 * (y as f32 + 0.5) / size as f32 - 1.0;
                    let d = (fwd + ndc_x * right - ndc_y * up).normalize();
                    rays.push(Ray::new(
                        [0.0; 3],
                        d.to_array(),
                        0.0,
                        f32::INFINITY,
                        MASK_GEOMETRY | MASK_LIGHTS,
                    ));
                }
            }
        }
    }
    rays
}

/// Cosine-distributed rays about the geometric normal from the first hits of `primary`
/// (`count` of them, cycling over the hits), as a path tracer's first bounce makes them.
pub fn bounce_rays(gpu: &GpuScene, primary: &[Ray], hits: &[HitRecord], count: usize) -> Vec<Ray> {
    let firsts: Vec<(Vec3, Vec3)> = primary
        .iter()
        .zip(hits)
        .filter(|(_, h)| h.kind == HIT_TRIANGLE)
        .map(|(r, h)| {
            let (mesh, rows) = gpu.instances[h.instance as usize];
            let m = gpu.meshes[mesh as usize];
            let base = (m.first_index + 3 * h.prim) as usize;
            let p = |k: usize| {
                let q = gpu.positions[(m.first_vertex + gpu.indices[base + k]) as usize];
                let row = |i: usize| Vec3::from_slice(&rows[i][..3]).dot(q) + rows[i][3];
                Vec3::new(row(0), row(1), row(2))
            };
            let (a, b, c) = (p(0), p(1), p(2));
            let mut n = (b - a).cross(c - a).normalize_or_zero();
            let d = Vec3::from_array(r.dir);
            if n.dot(d) > 0.0 {
                n = -n;
            }
            let w = Vec3::new(1.0 - h.bary[0] - h.bary[1], h.bary[0], h.bary[1]);
            let x = w.x * a + w.y * b + w.z * c;
            (x + n * (1e-4 * (1.0 + x.abs().max_element())), n)
        })
        .collect();
    if firsts.is_empty() {
        return Vec::new();
    }
    let mut state = 0x9e37_79b9u32;
    let mut rnd = || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        (state >> 8) as f32 / (1u32 << 24) as f32
    };
    (0..count)
        .map(|i| {
            let (o, n) = firsts[i % firsts.len()];
            let (t, b) = n.any_orthonormal_pair();
            let (u1, u2) = (rnd(), rnd());
            let r = u1.sqrt();
            let phi = std::f32::consts::TAU * u2;
            let d = (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt())
                .normalize();
            Ray::new(
                o.to_array(),
                d.to_array(),
                0.0,
                f32::INFINITY,
                MASK_GEOMETRY,
            )
        })
        .collect()
}

/// CPU time of this process so far (every thread), in seconds, where the OS tells it (Linux).
/// On a CPU device (lavapipe) the driver's threads are this process's, so rays per CPU-second
/// stay comparable when other processes share the machine; wall time does not.
pub fn process_cpu_seconds() -> Option<f64> {
    let tasks = std::fs::read_dir("/proc/self/task").ok()?;
    let mut ns = 0u64;
    for t in tasks.flatten() {
        let s = std::fs::read_to_string(t.path().join("schedstat")).ok()?;
        ns += s.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(ns as f64 * 1e-9)
}

/// A measurement: million rays per second of wall time, per CPU-second, and per second of the
/// dispatches' device time (timestamps; where the queue has them).
#[derive(Clone, Copy, Debug, Default)]
pub struct Rate {
    pub wall: f64,
    pub cpu: Option<f64>,
    pub device: Option<f64>,
}

/// One structure's figures on one mesh.
#[derive(Clone, Debug)]
pub struct BenchRow {
    pub triangles: u64,
    pub path: &'static str,
    pub build: BuildStats,
    /// Million rays per second: camera rays (closest hit), bounce rays with the first hit ending
    /// the query, and bounce rays to the closest hit.
    pub primary: Rate,
    pub bounce_any: Rate,
    pub bounce_closest: Rate,
    /// Fractions of camera and bounce rays that hit something.
    pub primary_hits: f64,
    pub bounce_hits: f64,
}

pub struct BenchOptions {
    pub triangles: Vec<usize>,
    /// Rays per measurement (camera rays form the largest square image not above it).
    pub rays: usize,
    /// Paths to measure; those the device lacks are skipped.
    pub paths: Vec<TraceMode>,
    /// Measurements of each figure; the best is reported (other load only slows things down).
    pub repeat: usize,
}

/// Runs the benchmark, calling `report` after each row.
pub fn run(ctx: &Context, opts: &BenchOptions, report: &mut dyn FnMut(&BenchRow)) -> Result<()> {
    for &n in &opts.triangles {
        let size = ((opts.rays as f64).sqrt() as u32).max(8);
        let scene = mesh_scene(displaced_sphere(n), DVec3::new(0.6, 0.8, 3.2), size);
        let mut bounce: Option<Vec<Ray>> = None;
        for &mode in &opts.paths {
            if mode == TraceMode::RayQuery && !ctx.ray_query() {
                continue;
            }
            let gpu = GpuScene::new(ctx, &scene, ctx.ray_query())?;
            let t0 = Instant::now();
            let trace = TraceStructure::build(ctx, &gpu, mode)?;
            let mut build = trace.build_stats().clone();
            if build.seconds() == 0.0 {
                build.tlas_seconds = t0.elapsed().as_secs_f64();
            }
            let kernel = QueryKernel::new(ctx, &gpu, &trace)?;
            let primary = camera_rays(&gpu, size);
            // Warm-up: first dispatches pay for lazy driver work.
            kernel.trace(ctx, &primary[..primary.len().min(4096)], QUERY_CLOSEST)?;
            let measure = |rays: &[Ray], mode| -> Result<(Vec<HitRecord>, Rate)> {
                let mut best = Rate::default();
                let mut hits = Vec::new();
                for _ in 0..opts.repeat.max(1) {
                    let cpu0 = process_cpu_seconds();
                    let (h, seconds, device) = kernel.trace(ctx, rays, mode)?;
                    let cpu = process_cpu_seconds().zip(cpu0).map(|(b, a)| b - a);
                    let mrays = |s: f64| rays.len() as f64 / s.max(1e-9) / 1e6;
                    best.wall = best.wall.max(mrays(seconds));
                    best.cpu = cpu.map(|c| mrays(c).max(best.cpu.unwrap_or(0.0)));
                    best.device = device.map(|d| mrays(d).max(best.device.unwrap_or(0.0)));
                    hits = h;
                }
                Ok((hits, best))
            };
            let (hits, primary_rate) = measure(&primary, QUERY_CLOSEST)?;
            // Bounce rays come from the first path measured, so that every path traces the same.
            let rays = bounce
                .get_or_insert_with(|| bounce_rays(&gpu, &primary, &hits, opts.rays))
                .clone();
            let (any, any_rate) = measure(&rays, QUERY_OCCLUDED)?;
            let (_, closest_rate) = measure(&rays, QUERY_CLOSEST)?;
            let frac = |k: usize, of: usize| k as f64 / of.max(1) as f64;
            report(&BenchRow {
                triangles: build.triangles,
                path: trace.name(),
                build,
                primary: primary_rate,
                bounce_any: any_rate,
                bounce_closest: closest_rate,
                primary_hits: frac(
                    hits.iter().filter(|h| h.kind != HIT_NONE).count(),
                    hits.len(),
                ),
                bounce_hits: frac(any.iter().filter(|h| h.occluded != 0).count(), any.len()),
            });
        }
    }
    Ok(())
}
