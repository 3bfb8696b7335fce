//! The two trace paths against each other and against an f64 reference: same instance, primitive
//! and t (1e-5 relative) for closest and any hit, on instanced and transformed meshes, a 100k-
//! triangle mesh, spheres, rects, disks, rays that start on surfaces and rays that graze edges;
//! and renders that agree. Tests that need ray queries skip (with a note) on devices without them;
//! the BVH tests run everywhere. Every test runs with the validation layers on.

mod common;
#[path = "trace/reference.rs"]
mod reference;

use common::{Rng, assert_no_validation_messages, context};
use glam::{DMat4, DQuat, DVec3, Vec3};
use illum::gpu_scene::GpuScene;
use illum::layout::*;
use illum::render::{RenderSettings, Renderer};
use illum::scene::*;
use illum::trace::bench::{camera_rays, displaced_sphere};
use illum::trace::query::{HitRecord, Ray, trace_rays};
use illum::trace::{TraceMode, TraceStructure};
use illum::vk::Context;

/// A uniform direction, the sphere's z as y: for a seed, the rays these tests were written with.
fn direction(rng: &mut Rng) -> DVec3 {
    let d = rng.sphere();
    DVec3::new(d.x, d.z, d.y)
}

fn grid(n: usize) -> Mesh {
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (
                i as f32 / n as f32 * 2.0 - 1.0,
                j as f32 / n as f32 * 2.0 - 1.0,
            );
            positions.push(Vec3::new(x, 0.0, z));
        }
    }
    let mut indices = Vec::new();
    for j in 0..n as u32 {
        for i in 0..n as u32 {
            let a = j * (n as u32 + 1) + i;
            let b = a + n as u32 + 1;
            indices.extend_from_slice(&[a, b, a + 1, a + 1, b, b + 1]);
        }
    }
    mesh("grid", positions, indices)
}

fn cube() -> Mesh {
    let positions = (0..8)
        .map(|k| Vec3::new((k & 1) as f32, ((k >> 1) & 1) as f32, ((k >> 2) & 1) as f32) - 0.5)
        .collect();
    let indices = vec![
        0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6,
        1, 3, 5, 3, 7, 5,
    ];
    mesh("cube", positions, indices)
}

fn mesh(name: &str, positions: Vec<Vec3>, indices: Vec<u32>) -> Mesh {
    Mesh {
        name: name.into(),
        positions,
        normals: None,
        tangents: None,
        uvs: None,
        indices,
        material: 0,
    }
}

fn material() -> Material {
    Material::lambert("grey", Vec3::splat(0.6))
}

fn light(kind: LightKind) -> Light {
    Light {
        name: "light".into(),
        kind,
        color: Vec3::ONE,
        intensity: 4.0,
        exposure: 0.0,
        two_sided: false,
        texture: None,
        visible: true,
        shadows: true,
    }
}

fn instance(mesh: u32, transform: DMat4) -> MeshInstance {
    MeshInstance {
        mesh,
        transform,
        name: format!("instance of {mesh}"),
    }
}

/// Instanced and transformed meshes (mirrored, non-uniformly scaled, a lone triangle, the same
/// mesh several times), analytic shapes, and visible area lights of every shape.
fn instanced_scene(width: u32, height: u32) -> Scene {
    let rot = |axis: DVec3, deg: f64| {
        DMat4::from_quat(DQuat::from_axis_angle(axis.normalize(), deg.to_radians()))
    };
    let t = DMat4::from_translation;
    let s = DMat4::from_scale;
    let tri = mesh(
        "triangle",
        vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ],
        vec![0, 1, 2],
    );
    Scene {
        camera: Camera {
            position: DVec3::new(0.5, 1.6, 6.5),
            look_at: DVec3::new(0.0, 0.2, 0.0),
            up: DVec3::Y,
            fov_y_deg: 55.0,
            width,
            height,
        },
        materials: vec![material()],
        textures: Vec::new(),
        meshes: vec![displaced_sphere(2000), grid(12), cube(), tri],
        instances: vec![
            instance(0, t(DVec3::new(-1.5, 0.2, 0.0)) * s(DVec3::splat(0.8))),
            instance(
                0,
                t(DVec3::new(1.6, 0.4, -0.5))
                    * rot(DVec3::new(1.0, 2.0, 0.5), 40.0)
                    * s(DVec3::new(1.4, 0.5, 0.9)),
            ),
            instance(1, t(DVec3::new(0.0, -1.0, 0.0)) * s(DVec3::splat(4.0))),
            // Mirrored wall (negative determinant).
            instance(
                1,
                t(DVec3::new(0.0, 1.0, -3.0)) * rot(DVec3::X, 90.0) * s(DVec3::new(-4.0, 1.0, 2.0)),
            ),
            instance(
                2,
                t(DVec3::new(0.3, -0.4, 1.2))
                    * rot(DVec3::new(0.3, 1.0, 0.2), 30.0)
                    * s(DVec3::splat(0.7)),
            ),
            instance(
                2,
                t(DVec3::new(-0.6, 1.8, -1.0)) * rot(DVec3::Z, 45.0) * s(DVec3::new(0.3, 1.5, 0.3)),
            ),
            instance(3, t(DVec3::new(-2.8, -0.5, 1.5)) * rot(DVec3::Y, 20.0)),
        ],
        shapes: vec![
            AnalyticShape {
                name: "ball".into(),
                geometry: ShapeGeometry::Sphere {
                    center: DVec3::new(0.0, 0.0, 0.8),
                    radius: 0.5,
                },
                material: 0,
                pole: None,
            },
            AnalyticShape {
                name: "panel".into(),
                geometry: ShapeGeometry::Rect {
                    center: DVec3::new(2.6, 0.2, 1.0),
                    u: DVec3::new(0.0, 1.2, 0.0),
                    v: DVec3::new(0.6, 0.0, -0.8),
                },
                material: 0,
                pole: None,
            },
            AnalyticShape {
                name: "disk".into(),
                geometry: ShapeGeometry::Disk {
                    center: DVec3::new(-0.8, -0.2, 2.2),
                    normal: DVec3::new(0.2, 1.0, 0.4),
                    radius: 0.45,
                },
                material: 0,
                pole: None,
            },
        ],
        lights: vec![
            light(LightKind::Rect {
                center: DVec3::new(0.0, 2.8, 0.0),
                u: DVec3::new(1.0, 0.0, 0.0),
                v: DVec3::new(0.0, 0.0, 0.8),
            }),
            light(LightKind::Disk {
                center: DVec3::new(-2.5, 2.0, 1.0),
                normal: DVec3::new(0.5, -1.0, 0.0),
                radius: 0.3,
            }),
            light(LightKind::Sphere {
                center: DVec3::new(2.2, 2.2, -1.0),
                radius: 0.25,
            }),
        ],
        description: None,
        integrator: Default::default(),
        warnings: Vec::new(),
        inputs: Vec::new(),
        source: None,
    }
}

fn big_mesh_scene() -> Scene {
    let mut s = instanced_scene(64, 64);
    s.meshes = vec![displaced_sphere(100_000)];
    s.instances = vec![instance(
        0,
        DMat4::from_rotation_y(0.3) * DMat4::from_scale(DVec3::splat(1.5)),
    )];
    s.shapes.clear();
    s.lights.clear();
    s.camera.position = DVec3::new(0.4, 0.9, 4.0);
    s
}

/// Camera rays, rays from random points in random directions (random t ranges and masks), rays
/// starting on the surfaces the camera sees, and rays aimed at triangle edges and vertices and
/// along the floor's plane. Returns the rays and where the grazing ones (made to be ties) start.
fn rays(
    gpu: &GpuScene,
    camera_hits: &[HitRecord],
    camera: &[Ray],
    rng: &mut Rng,
    n: usize,
) -> (Vec<Ray>, usize) {
    let mut out = camera.to_vec();
    let cam = |p: DVec3| p.as_vec3().to_array();
    let masks = [MASK_GEOMETRY, MASK_LIGHTS, MASK_GEOMETRY | MASK_LIGHTS, 0];
    for k in 0..n {
        let o = DVec3::new(
            8.0 * rng.uniform() - 4.0,
            4.5 * rng.uniform() - 1.5,
            8.0 * rng.uniform() - 4.0,
        ) - DVec3::new(0.5, 1.6, 6.5);
        let tmax = if k % 3 == 0 {
            0.5 + 5.0 * rng.uniform()
        } else {
            f64::INFINITY
        };
        let tmin = if k % 4 == 0 { 0.01 } else { 0.0 };
        out.push(Ray::new(
            cam(o),
            cam(direction(rng)),
            tmin as f32,
            tmax as f32,
            masks[k % 4],
        ));
    }
    // On surfaces: exactly at the hit point (from the hit's barycentrics), any direction.
    for (r, h) in camera
        .iter()
        .zip(camera_hits)
        .filter(|(_, h)| h.kind != HIT_NONE)
        .take(n)
    {
        let p = DVec3::from_array(r.dir.map(f64::from)) * f64::from(h.t);
        let p = if h.kind == HIT_TRIANGLE {
            surface_point(gpu, h)
        } else {
            p
        };
        out.push(Ray::new(
            cam(p),
            cam(direction(rng)),
            1e-3,
            f32::INFINITY,
            MASK_GEOMETRY | MASK_LIGHTS,
        ));
    }
    // Grazing: at edge midpoints and vertices of triangles (the floor grid, the cube), from
    // random points; and along the floor's plane.
    let grazing = out.len();
    let instances = gpu.instances.len();
    for k in 0..(n / 2) * usize::from(instances > 0) {
        let inst = [2, 4, k / 8][k % 8 / 4].min(instances - 1) as u32;
        let tris = gpu.meshes[gpu.instances[inst as usize].0 as usize].triangle_count;
        let bary = [[0.5, 0.0], [0.5, 0.5], [0.0, 0.0], [0.0, 0.5]][k % 4];
        let h = HitRecord {
            instance: inst,
            prim: (k * 7919) as u32 % tris,
            bary,
            ..Default::default()
        };
        let target = surface_point(gpu, &h);
        let o = target + direction(rng) * (1.0 + 3.0 * rng.uniform());
        out.push(Ray::new(
            cam(o),
            cam((target - o).normalize()),
            0.0,
            f32::INFINITY,
            MASK_GEOMETRY,
        ));
    }
    if instances > 2 {
        let floor = surface_point(
            gpu,
            &HitRecord {
                instance: 2,
                prim: 40,
                ..Default::default()
            },
        );
        for k in 0..32 {
            let a = std::f64::consts::TAU * k as f64 / 32.0;
            let d = DVec3::new(a.cos(), 0.0, a.sin());
            out.push(Ray::new(
                cam(floor - d * 3.0),
                cam(d),
                0.0,
                f32::INFINITY,
                MASK_GEOMETRY,
            ));
        }
    }
    (out, grazing)
}

/// Render-space point of a triangle hit, from the vertices.
fn surface_point(gpu: &GpuScene, h: &HitRecord) -> DVec3 {
    let (mesh, rows) = gpu.instances[h.instance as usize];
    let m = gpu.meshes[mesh as usize];
    let base = (m.first_index + 3 * h.prim) as usize;
    let p = |k: usize| {
        let q = gpu.positions[(m.first_vertex + gpu.indices[base + k]) as usize].as_dvec3();
        DVec3::from_array([0, 1, 2].map(|r| {
            glam::DVec4::from_array(rows[r].map(f64::from))
                .truncate()
                .dot(q)
                + f64::from(rows[r][3])
        }))
    };
    let (b1, b2) = (f64::from(h.bary[0]), f64::from(h.bary[1]));
    p(0) * (1.0 - b1 - b2) + p(1) * b1 + p(2) * b2
}

/// Whether two answers are the same: kind, instance, primitive, t within the tolerance, the
/// points the barycentrics name within the same tolerance, and the occlusion answer.
fn same(gpu: &GpuScene, ray: &Ray, a: &HitRecord, b: &HitRecord) -> bool {
    let t = f64::from(a.t);
    let tol = reference::t_tolerance(ray, t);
    a.kind == b.kind
        && a.occluded == b.occluded
        && (a.kind == HIT_NONE
            || (a.instance == b.instance
                && a.prim == b.prim
                && (t - f64::from(b.t)).abs() <= tol
                && (a.kind == HIT_SHAPE
                    || surface_point(gpu, a).distance(surface_point(gpu, b)) <= tol)))
}

fn build(ctx: &Context, gpu: &GpuScene, mode: TraceMode) -> TraceStructure {
    TraceStructure::build(ctx, gpu, mode).unwrap_or_else(|e| panic!("building {mode:?}: {e}"))
}

fn skip_without_ray_query(ctx: &Context) -> bool {
    if !ctx.ray_query() {
        eprintln!(
            "note: {} has no VK_KHR_ray_query; skipping the ray-query comparison",
            ctx.info().name
        );
        return true;
    }
    false
}

/// Traces the same rays on both paths; they must agree, except on rays where the reference says
/// both answers are right (ties at shared edges, grazing hits), and those must be rare.
fn compare_paths(scene: &Scene, n: usize) {
    let ctx = context();
    if skip_without_ray_query(&ctx) {
        return;
    }
    let gpu = GpuScene::new(&ctx, scene, true).unwrap();
    let rq = build(&ctx, &gpu, TraceMode::RayQuery);
    let bvh = build(&ctx, &gpu, TraceMode::Bvh);
    let camera = camera_rays(&gpu, scene.camera.width);
    let camera_hits = trace_rays(&ctx, &gpu, &bvh, &camera).unwrap();
    let (rays, grazing) = rays(&gpu, &camera_hits, &camera, &mut Rng::new(7), n);
    let a = trace_rays(&ctx, &gpu, &rq, &rays).unwrap();
    let b = trace_rays(&ctx, &gpu, &bvh, &rays).unwrap();
    let (mut differ, mut ties) = (0, 0);
    let mut max_rel = 0.0f64;
    for (i, r) in rays.iter().enumerate() {
        if same(&gpu, r, &a[i], &b[i]) {
            if a[i].kind != HIT_NONE {
                let dt = f64::from((a[i].t - b[i].t).abs());
                max_rel = max_rel.max(dt / reference::t_tolerance(r, f64::from(a[i].t)) * 1e-5);
            }
            continue;
        }
        if i < grazing {
            differ += 1;
        } else {
            ties += 1;
        }
        if std::env::var("ILLUM_TRACE_DEBUG").is_ok() {
            let (x, y) = (&a[i], &b[i]);
            let what = if x.kind != y.kind {
                "kind"
            } else if x.instance != y.instance || x.prim != y.prim {
                "prim"
            } else if x.occluded != y.occluded {
                "occluded"
            } else if x.t != y.t
                && (x.bary[0] - y.bary[0]).abs() <= 1e-4
                && (x.bary[1] - y.bary[1]).abs() <= 1e-4
            {
                "t"
            } else {
                "bary"
            };
            eprintln!("{i} {what}: rq {x:?} bvh {y:?}");
        }
        for (name, rec) in [("rayquery", &a[i]), ("bvh", &b[i])] {
            if let Some(why) = reference::judge(&gpu, r, rec) {
                panic!(
                    "ray {i} {r:?}: {name} answer {rec:?} is wrong: {why}\n(the other: {:?})",
                    if name == "bvh" { &a[i] } else { &b[i] }
                );
            }
        }
    }
    let hit = b.iter().filter(|h| h.kind != HIT_NONE).count();
    eprintln!(
        "{} rays, {hit} hits: {differ} of {grazing} differ, and {ties} of {} aimed at edges and \
         vertices (answers the reference allows); largest t difference {max_rel:.1e} of (t + |origin|)",
        rays.len(),
        rays.len() - grazing
    );
    assert!(hit > rays.len() / 4, "too few hits to test anything");
    assert!(differ * 200 <= grazing, "{differ} of {grazing} rays differ");
    assert_no_validation_messages(&ctx);
}

#[test]
fn paths_agree_on_instanced_meshes_and_shapes() {
    compare_paths(&instanced_scene(64, 48), 3000);
}

#[test]
fn paths_agree_on_a_100k_triangle_mesh() {
    compare_paths(&big_mesh_scene(), 3000);
}

/// On every device (the stock driver has no ray queries): the BVH against the f64 reference.
#[test]
fn bvh_matches_the_reference() {
    let ctx = context();
    let scene = instanced_scene(32, 24);
    let gpu = GpuScene::new(&ctx, &scene, ctx.ray_query()).unwrap();
    let bvh = build(&ctx, &gpu, TraceMode::Bvh);
    assert_eq!(bvh.name(), "bvh");
    let camera = camera_rays(&gpu, 32);
    let camera_hits = trace_rays(&ctx, &gpu, &bvh, &camera).unwrap();
    let (rays, _) = rays(&gpu, &camera_hits, &camera, &mut Rng::new(11), 600);
    let got = trace_rays(&ctx, &gpu, &bvh, &rays).unwrap();
    for (i, (r, h)) in rays.iter().zip(&got).enumerate() {
        if let Some(why) = reference::judge(&gpu, r, h) {
            panic!("ray {i} {r:?}: {h:?} is wrong: {why}");
        }
        assert_eq!(
            h.occluded != 0,
            h.kind != HIT_NONE,
            "ray {i}: closest and any hit disagree"
        );
    }
    assert!(got.iter().filter(|h| h.kind == HIT_SHAPE).count() > 10);
    assert!(got.iter().filter(|h| h.kind == HIT_TRIANGLE).count() > 100);
    assert_no_validation_messages(&ctx);
}

/// Scenes whose top level is one leaf, has only shapes, or is empty of anything a mask selects.
#[test]
fn bvh_handles_small_and_degenerate_scenes() {
    let ctx = context();
    let mut only_triangle = instanced_scene(8, 8);
    only_triangle.instances = vec![instance(
        3,
        DMat4::from_translation(DVec3::new(0.0, 0.0, 0.0)),
    )];
    only_triangle.shapes.clear();
    only_triangle.lights.clear();
    let mut only_shapes = instanced_scene(8, 8);
    only_shapes.instances.clear();
    // Many copies of one triangle: no split plane separates them.
    let mut stacked = instanced_scene(8, 8);
    stacked.meshes[3].indices = [0, 1, 2].repeat(100);
    stacked.instances = vec![instance(3, DMat4::IDENTITY)];
    for scene in [only_triangle, only_shapes, stacked] {
        let gpu = GpuScene::new(&ctx, &scene, ctx.ray_query()).unwrap();
        let bvh = build(&ctx, &gpu, TraceMode::Bvh);
        let camera = camera_rays(&gpu, 8);
        let hits = trace_rays(&ctx, &gpu, &bvh, &camera).unwrap();
        let (rays, _) = rays(&gpu, &hits, &camera, &mut Rng::new(3), 64);
        let got = trace_rays(&ctx, &gpu, &bvh, &rays).unwrap();
        for (i, (r, h)) in rays.iter().zip(&got).enumerate() {
            if let Some(why) = reference::judge(&gpu, r, h) {
                panic!("ray {i} {r:?}: {h:?} is wrong: {why}");
            }
        }
    }
    assert_no_validation_messages(&ctx);
}

#[test]
fn bvh_kernels_declare_no_ray_query_capability() {
    const OP_CAPABILITY: u32 = 17;
    const RAY_QUERY_KHR: u32 = 4472;
    let capabilities = |spv: &[u8]| -> Vec<u32> {
        let words: Vec<u32> = spv
            .chunks(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        let mut caps = Vec::new();
        let mut i = 5;
        while i < words.len() {
            let (count, op) = ((words[i] >> 16) as usize, words[i] & 0xffff);
            if op == OP_CAPABILITY {
                caps.push(words[i + 1]);
            }
            i += count.max(1);
        }
        caps
    };
    for spv in [illum::shaders::PRIMARY_BVH, illum::shaders::TRACE_QUERY_BVH] {
        assert!(!capabilities(spv).contains(&RAY_QUERY_KHR));
    }
    for spv in [illum::shaders::PRIMARY_RQ, illum::shaders::TRACE_QUERY_RQ] {
        assert!(capabilities(spv).contains(&RAY_QUERY_KHR));
    }
}

/// The same scene and seed rendered on both paths: beauty, depth and normal AOVs agree.
#[test]
fn renders_agree_between_paths() {
    let ctx = context();
    if skip_without_ray_query(&ctx) {
        return;
    }
    let scene = instanced_scene(96, 72);
    let renderer = Renderer::new(ctx.clone());
    let render = |trace| {
        let settings = RenderSettings {
            spp: 4,
            seed: 5,
            trace,
            ..Default::default()
        };
        renderer.render(&scene, &settings, &mut |_, _| {}).unwrap()
    };
    let (a, b) = (render(TraceMode::RayQuery), render(TraceMode::Bvh));
    assert_eq!((a.stats.trace, b.stats.trace), ("rayquery", "bvh"));
    let (fa, fb) = (&a.film, &b.film);
    let n = fa.depth.len();
    let mut differ = 0;
    let (mut sum_a, mut sum_b) = (0.0f64, 0.0f64);
    for i in 0..n {
        let close = |x: f32, y: f32| (x - y).abs() <= 1e-4 * (1.0 + x.abs()) || x == y;
        let ok = close(fa.depth[i], fb.depth[i])
            && (0..3).all(|c| {
                close(fa.normal[i][c], fb.normal[i][c]) && close(fa.beauty[i][c], fb.beauty[i][c])
            });
        if !ok {
            differ += 1;
        }
        sum_a += fa.beauty[i].iter().map(|&v| f64::from(v)).sum::<f64>();
        sum_b += fb.beauty[i].iter().map(|&v| f64::from(v)).sum::<f64>();
    }
    eprintln!(
        "{differ} of {n} pixels differ; mean beauty {:.5} vs {:.5}",
        sum_a / n as f64,
        sum_b / n as f64
    );
    assert!(differ * 100 <= n, "{differ} of {n} pixels differ");
    assert!(
        (sum_a - sum_b).abs() <= 1e-3 * sum_a.abs(),
        "mean beauty {sum_a} vs {sum_b}"
    );
    assert!(fb.depth.iter().filter(|z| z.is_finite()).count() > n / 2);
    assert_no_validation_messages(&ctx);
}

/// A mesh of 1.2M identical triangles: its SAH tree needed about 57 stack entries, past the
/// kernels' 48, and the default trace path refused it. The compute BVH now builds such meshes
/// balanced (src/trace/bvh/mod.rs) and renders them.
#[test]
fn the_compute_bvh_takes_degenerate_meshes() {
    let ctx = context();
    let n = 1_200_000;
    let tri = mesh(
        "identical",
        vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ],
        [0u32, 1, 2].repeat(n),
    );
    let scene = Scene {
        camera: Camera {
            position: DVec3::new(0.0, 0.0, 3.0),
            look_at: DVec3::ZERO,
            up: DVec3::Y,
            fov_y_deg: 30.0,
            width: 9,
            height: 9,
        },
        materials: vec![material()],
        textures: Vec::new(),
        meshes: vec![tri],
        instances: vec![instance(0, DMat4::IDENTITY)],
        shapes: Vec::new(),
        lights: vec![light(LightKind::Dome {
            rotation_deg: 0.0,
            convention: Default::default(),
        })],
        description: None,
        source: None,
        integrator: Default::default(),
        warnings: Vec::new(),
        inputs: Vec::new(),
    };
    let settings = RenderSettings {
        spp: 1,
        trace: TraceMode::Bvh,
        ..Default::default()
    };
    let out = Renderer::new(ctx.clone())
        .render(&scene, &settings, &mut |_, _| {})
        .unwrap_or_else(|e| panic!("the compute BVH refused the mesh: {e}"));
    let z = out.film.depth[4 * 9 + 4];
    assert!((z - 3.0).abs() < 1e-3, "depth {z}");
    assert!(
        out.stats.build.max_stack <= BVH_STACK_SIZE,
        "{}",
        out.stats.build.max_stack
    );
    eprintln!(
        "1.2M identical triangles: walk stack {}",
        out.stats.build.max_stack
    );
    assert_no_validation_messages(&ctx);
}

/// A closed room of analytic shapes around the shapes and lights of `instanced_scene`, no meshes:
/// traced flat (FEATURE_FLAT_SHAPES).
fn closed_room_scene() -> Scene {
    let mut scene = instanced_scene(24, 16);
    scene.meshes.clear();
    scene.instances.clear();
    let wall = |name: &str, center: DVec3, u: DVec3, v: DVec3| AnalyticShape {
        name: name.into(),
        geometry: ShapeGeometry::Rect { center, u, v },
        material: 0,
        pole: None,
    };
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    scene.shapes.extend([
        wall("floor", DVec3::new(0.0, -2.0, 1.0), 12.0 * x, 14.0 * z),
        wall("ceiling", DVec3::new(0.0, 5.0, 1.0), 12.0 * x, 14.0 * z),
        wall("left", DVec3::new(-6.0, 1.5, 1.0), 7.0 * y, 14.0 * z),
        wall("right", DVec3::new(6.0, 1.5, 1.0), 7.0 * y, 14.0 * z),
        wall("back", DVec3::new(0.0, 1.5, -6.0), 12.0 * x, 7.0 * y),
        wall("front", DVec3::new(0.0, 1.5, 8.0), 12.0 * x, 7.0 * y),
    ]);
    scene
}

/// The flat test of every shape (FEATURE_FLAT_SHAPES) against the BVH walk of the same scene (its feature bit cleared)
/// and the f64 reference: the same answers, bit for bit, except rays aimed at edges, where two
/// shapes at the same distance may be told apart differently.
#[test]
fn flat_shapes_agree_with_the_walk_and_the_reference() {
    let ctx = context();
    let scene = closed_room_scene();
    let mut gpu = GpuScene::new(&ctx, &scene, ctx.ray_query()).unwrap();
    assert_ne!(
        gpu.features & FEATURE_FLAT_SHAPES,
        0,
        "the room is not traced flat"
    );
    // Past BVH_FLAT_MAX shapes the BVH is walked.
    let mut more = scene.clone();
    while more.shapes.len() + more.lights.len() <= BVH_FLAT_MAX as usize {
        more.shapes.push(more.shapes[0].clone());
    }
    let more = GpuScene::new(&ctx, &more, ctx.ray_query()).unwrap();
    assert_eq!(
        more.features & FEATURE_FLAT_SHAPES,
        0,
        "{} shapes",
        more.shapes.len()
    );
    let bvh = build(&ctx, &gpu, TraceMode::Bvh);
    let camera = camera_rays(&gpu, 24);
    let camera_hits = trace_rays(&ctx, &gpu, &bvh, &camera).unwrap();
    let (rays, grazing) = rays(&gpu, &camera_hits, &camera, &mut Rng::new(5), 3000);
    let flat = trace_rays(&ctx, &gpu, &bvh, &rays).unwrap();
    gpu.features &= !FEATURE_FLAT_SHAPES;
    let walk = trace_rays(&ctx, &gpu, &bvh, &rays).unwrap();
    let mut differ = 0;
    for (i, r) in rays.iter().enumerate() {
        if let Some(why) = reference::judge(&gpu, r, &flat[i]) {
            panic!("ray {i} {r:?}: flat answer {:?} is wrong: {why}", flat[i]);
        }
        let (a, b) = (&flat[i], &walk[i]);
        let same = a.kind == b.kind
            && a.prim == b.prim
            && a.t.to_bits() == b.t.to_bits()
            && a.occluded == b.occluded;
        if !same && i < grazing {
            differ += 1;
        }
    }
    let hits = flat.iter().filter(|h| h.kind == HIT_SHAPE).count();
    assert!(
        hits > rays.len() / 4,
        "too few hits to test anything: {hits}"
    );
    assert_eq!(
        differ, 0,
        "{differ} of {grazing} rays differ between flat and walked"
    );
    assert_no_validation_messages(&ctx);
}
