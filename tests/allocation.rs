//! The measured sample allocation (src/render/allocation/, docs/allocation.md): every
//! allocation the pilot can choose is unbiased (a closed form); the pilot raises the floor
//! under one small light and keeps the course's share rule with many lights, where extra
//! samples cost more than they remove; it picks lights from the light tree under small
//! spheres, and loops over rect lights whose loop is nearly free of noise; and the jobs of a split render decide the same
//! allocation and merge bit-identically to one render.

mod common;
use common::*;
use glam::DVec3;
use illum::integrators::Direct;
use illum::jobs::{Part, merge};
use illum::render::allocation::{Allocation, Counts};
use illum::render::{RenderSettings, Renderer};

const ALBEDO: f64 = 0.5;

/// A Lambert floor under a small disk light (radius 0.2 at height 1: a share of a few percent),
/// seen from the side through a narrow field of view.
const DISK: &str = r#"{"camera": {"position": [6, 1, 0.3], "look_at": [0, 0, 0], "fov_y": 6, "resolution": [16, 16]},
    "materials": {"m": {"diffuse": [0.5, 0.5, 0.5]}},
    "shapes": {"floor": {"rect": {"center": [0, 0, 0], "normal": [0, 1, 0], "size": [40, 40]}, "material": "m"}},
    "lights": {"l": {"disk": {"center": [0, 1, 0], "normal": [0, -1, 0], "radius": 0.2}, "intensity": 20}}}"#;

/// The disks of `disks()`: (x, z) of each centre, at height 1, radius 0.2, facing down.
const DISK_GRID: [(f64, f64); 9] = [
    (-0.6, -0.6),
    (0.0, -0.6),
    (0.6, -0.6),
    (-0.6, 0.0),
    (0.0, 0.0),
    (0.6, 0.0),
    (-0.6, 0.6),
    (0.0, 0.6),
    (0.6, 0.6),
];

/// DISK's floor under nine such disks (DISK_GRID), each of a ninth of its power: more lights
/// than LIGHT_TREE_MIN_LIGHTS, so a light tree, and the loop or the tree to pick from.
fn disks() -> String {
    let l: Vec<String> = DISK_GRID
        .iter()
        .enumerate()
        .map(|(k, (x, z))| {
            format!(
                r#""l{k}": {{"disk": {{"center": [{x}, 1, {z}], "normal": [0, -1, 0], "radius": 0.2}}, "intensity": {}}}"#,
                20.0 / 9.0
            )
        })
        .collect();
    DISK.replace(
        r#""l": {"disk": {"center": [0, 1, 0], "normal": [0, -1, 0], "radius": 0.2}, "intensity": 20}"#,
        &l.join(", "),
    )
}

/// A closed form of a floor point's irradiance.
type Irradiance<'a> = dyn Fn(DVec3) -> f64 + 'a;

#[test]
fn every_allocation_the_pilot_can_choose_matches_the_closed_form() {
    // A disk's vector irradiance at p, the disk of radiance l at (cx, h, cz) (tests/direct.rs).
    let (h, r) = (1.0, 0.2);
    let disk = |p: DVec3, cx: f64, cz: f64, l: f64| {
        let a2 = (p.x - cx).powi(2) + (p.z - cz).powi(2);
        let s = h * h + a2 + r * r;
        let q = (s * s - 4.0 * a2 * r * r).sqrt();
        l * std::f64::consts::PI / 2.0 * (1.0 - (h * h + a2 - r * r) / q)
    };
    let one = |p: DVec3| disk(p, 0.0, 0.0, 20.0);
    let nine = |p: DVec3| {
        DISK_GRID
            .iter()
            .map(|(x, z)| disk(p, *x, *z, 20.0 / 9.0))
            .sum()
    };
    let pts = floor_points(DVec3::new(6.0, 1.0, 0.3), 6.0, 16, 16);
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    let start = Counts {
        tree: false,
        light_samples: 4,
        brdf_samples: 2,
        dome_samples: 8,
        light_floor: 1,
        diffuse_mis: false,
    };
    // The floor lifted to N_max, and N_max, the BRDF samples and diffuse MIS moved with it; the
    // light tree in place of the loop, with N_max moved.
    let cases: [(String, &Irradiance<'_>, Counts); 5] = [
        (
            DISK.to_string(),
            &one,
            Counts {
                light_floor: 4,
                ..start
            },
        ),
        (
            DISK.to_string(),
            &one,
            Counts {
                light_samples: 8,
                brdf_samples: 1,
                light_floor: 8,
                diffuse_mis: true,
                ..start
            },
        ),
        (disks(), &nine, start),
        (
            disks(),
            &nine,
            Counts {
                tree: true,
                ..start
            },
        ),
        (
            disks(),
            &nine,
            Counts {
                tree: true,
                light_samples: 2,
                ..start
            },
        ),
    ];
    let mut means = Vec::new();
    for (json, irradiance, counts) in cases {
        let settings = RenderSettings {
            spp: 64,
            seed: 3,
            trace: trace_mode(),
            allocation: Some(Allocation {
                counts,
                how: "test".into(),
            }),
            ..Default::default()
        };
        let b = Batches::render(&renderer, &scene(&json), &settings, BATCHES);
        assert_lambert_floor(&b, &pts, ALBEDO, irradiance);
        means.push(b.mean);
    }
    // The tree ran: the same seeds give another image than the loop's.
    assert_ne!(means[2], means[3], "the tree's image is the loop's");
    assert_no_validation_messages(&ctx);
}

/// 16 small sphere lights on a 4 x 4 grid over a floor and a ball.
fn grid() -> String {
    let mut l = Vec::new();
    for k in 0..16 {
        let (x, z) = ((k % 4) as f64 - 1.5, (k / 4) as f64 - 1.5);
        l.push(format!(
            r#""l{k}": {{"sphere": {{"center": [{x}, 1, {z}], "radius": 0.05}}, "intensity": 40}}"#
        ));
    }
    with_lights(&l.join(", "))
}

/// 16 rect lights, 0.25 x 0.25, on a 4 x 4 grid 2.5 above the floor, facing down.
fn rects() -> String {
    let mut l = Vec::new();
    for k in 0..16 {
        let (x, z) = ((k % 4) as f64 - 1.5, (k / 4) as f64 - 1.5);
        l.push(format!(
            r#""l{k}": {{"rect": {{"center": [{x}, 2.5, {z}], "normal": [0, -1, 0], "size": [0.25, 0.25]}}, "intensity": 20}}"#
        ));
    }
    with_lights(&l.join(", "))
}

/// 64 small sphere lights on an 8 x 8 grid, 0.8 apart and 0.8 above the floor: each point is lit
/// mostly by the few lights nearest it, which the light tree finds and a loop pays for all.
fn spread() -> String {
    let mut l = Vec::new();
    for k in 0..64 {
        let (x, z) = (((k % 8) as f64 - 3.5) * 0.8, ((k / 8) as f64 - 3.5) * 0.8);
        l.push(format!(
            r#""l{k}": {{"sphere": {{"center": [{x}, 0.8, {z}], "radius": 0.04}}, "intensity": 40}}"#
        ));
    }
    with_lights(&l.join(", "))
}

/// One 0.8 x 0.8 rect light 1.2 above the floor and the ball: a share of 5% (one sample by the
/// course's rule), and a penumbra that more samples resolve.
fn one_rect() -> String {
    with_lights(
        r#""key": {"rect": {"center": [0, 1.2, 0], "normal": [0, -1, 0], "size": [0.8, 0.8]}, "intensity": 10}"#,
    )
}

fn with_lights(lights: &str) -> String {
    format!(
        r#"{{"camera": {{"position": [0, 3, 5], "look_at": [0, 0, 0], "fov_y": 45, "resolution": [128, 96]}},
            "materials": {{"m": {{"diffuse": [0.5, 0.5, 0.5]}},
                           "b": {{"diffuse": [0.6, 0.4, 0.3]}}}},
            "shapes": {{"floor": {{"rect": {{"center": [0, 0, 0], "normal": [0, 1, 0], "size": [10, 10]}}, "material": "m"}},
                       "ball": {{"sphere": {{"center": [0.3, 0.35, 0.2], "radius": 0.35}}, "material": "b"}}}},
            "lights": {{{lights}}}}}"#
    )
}

#[test]
fn the_pilot_lifts_the_floor_for_one_light_and_picks_the_tree_only_where_it_pays() {
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    // A render large enough for a pilot (its spp sizes the pilot; nothing else is rendered).
    let settings = RenderSettings {
        spp: 4096,
        trace: trace_mode(),
        integrator: std::sync::Arc::new(Direct::measured()),
        ..Default::default()
    };
    let decide = |json: &str| {
        let scene = scene(json);
        let prepared = renderer.prepare(&scene, settings.trace).unwrap();
        let (s, seconds) = renderer
            .decide_allocation(&prepared, &scene.camera, &settings)
            .unwrap();
        let a = s.allocation.expect("a decided allocation");
        assert!(a.how.starts_with("measured"), "{}", a.how);
        assert!(seconds > 0.0);
        a.counts
    };
    let one = decide(&one_rect());
    assert_eq!(
        one.light_floor, one.light_samples,
        "one small light: {one:?}"
    );
    let many = decide(&grid());
    assert_eq!(many.light_floor, 1, "16 small lights: {many:?}");
    // Picks from the light tree pay under small spheres (at equal time, 4 s: relMSE 0.18-0.26×
    // the loop's under grid(), 0.05-0.11× under spread()), not under 16 rects 2.5 above the
    // floor, whose loop is nearly free of noise (the tree's: ~300× the loop's on a glossy floor).
    assert!(many.tree, "16 small sphere lights: {many:?}");
    let spread = decide(&spread());
    assert!(spread.tree, "64 small sphere lights spread out: {spread:?}");
    let rects = decide(&rects());
    assert!(!rects.tree, "16 rect lights: {rects:?}");
    // Given counts are kept as given.
    let fixed = RenderSettings {
        integrator: std::sync::Arc::new(Direct::default()),
        ..settings.clone()
    };
    let scene = scene(&one_rect());
    let prepared = renderer.prepare(&scene, settings.trace).unwrap();
    let (s, seconds) = renderer
        .decide_allocation(&prepared, &scene.camera, &fixed)
        .unwrap();
    assert!(s.allocation.is_none() && seconds == 0.0);
    assert_no_validation_messages(&ctx);
}

#[test]
fn jobs_decide_the_same_allocation_and_merge_bit_identically() {
    let ctx = context();
    let renderer = Renderer::new(ctx.clone());
    let mut scene = scene(SMALL_SCENE);
    // 256 x 176 pixels at 64 spp: large enough for a pilot of 1024 pixels (few samples a
    // pixel: drivers that cut long loops short submit each sample apart).
    (scene.camera.width, scene.camera.height) = (256, 176);
    let settings =
        |samples: Option<(u32, u32)>, crop: Option<illum::film::Window>| RenderSettings {
            spp: 64,
            seed: 5,
            trace: trace_mode(),
            samples,
            crop,
            ..Default::default()
        };
    let whole = renderer
        .render(&scene, &settings(None, None), &mut |_, _| {})
        .unwrap();
    let allocation = |o: &illum::render::RenderOutput| {
        o.stats
            .integrator
            .iter()
            .find(|(k, _)| k == "allocation")
            .map(|(_, v)| v.clone())
            .expect("an allocation in the render's figures")
    };
    let decided = allocation(&whole);
    assert!(decided.contains("measured"), "{decided}");
    let jobs = [
        settings(Some((0, 23)), None),
        settings(Some((23, 64)), None),
    ];
    // Jobs that decided otherwise would not add up to the whole render.
    let parts: Vec<Part> = jobs
        .iter()
        .enumerate()
        .map(|(k, s)| render_part(&renderer, &scene, s, &format!("allocation-range-{k}")))
        .collect();
    assert_eq!(merge(&parts).unwrap().film, whole.film, "sample ranges");
    let crops = [
        illum::film::Window {
            x0: 0,
            y0: 0,
            x1: 256,
            y1: 53,
        },
        illum::film::Window {
            x0: 0,
            y0: 53,
            x1: 256,
            y1: 176,
        },
    ];
    let parts: Vec<Part> = crops
        .iter()
        .enumerate()
        .map(|(k, w)| {
            render_part(
                &renderer,
                &scene,
                &settings(None, Some(*w)),
                &format!("allocation-crop-{k}"),
            )
        })
        .collect();
    assert_eq!(merge(&parts).unwrap().film, whole.film, "crops");
    assert_no_validation_messages(&ctx);
}
