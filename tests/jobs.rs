//! Split renders (issue 10): jobs by sample range (aligned to the film's 256-sample blocks or
//! not) and by pixel window, written as partial EXRs, read back and merged, give the render in
//! one piece bit for bit, on both trace paths; merging refuses parts that do not belong together,
//! naming the part and the field.

mod common;
use common::*;
use illum::output::partial::{read_partial, write_partial};
use illum::render::job::{Part, merge, part_info};
use illum::render::{RenderSettings, Renderer, Window};
use illum::trace::TraceMode;

/// Odd sizes everywhere: 13x9 pixels, 600 samples (blocks 0..256, 256..512, 512..600).
const SCENE: &str = r#"{"camera": {"position": [0, 1.2, 3], "look_at": [0, 0.3, 0], "fov_y": 40, "resolution": [13, 9]},
    "materials": {"floor": {"diffuse": [0.6, 0.6, 0.6], "specular": [{"model": "ggx", "roughness": 0.2}]},
                  "ball": {"diffuse": [0.7, 0.3, 0.2]}},
    "shapes": {"floor": {"rect": {"center": [0, 0, 0], "normal": [0, 1, 0], "size": [6, 6]}, "material": "floor"},
               "ball": {"sphere": {"center": [0, 0.5, 0], "radius": 0.5}, "material": "ball"}},
    "lights": {"key": {"rect": {"center": [1, 2, 1], "normal": [-0.4, -1, -0.4], "size": [0.8, 0.8]}, "intensity": 6},
               "sky": {"dome": {}, "color": [0.2, 0.3, 0.4]}}}"#;
const SPP: u32 = 600;

fn settings(
    trace: TraceMode,
    seed: u64,
    samples: Option<(u32, u32)>,
    crop: Option<Window>,
) -> RenderSettings {
    RenderSettings {
        spp: SPP,
        seed,
        trace,
        samples,
        crop,
        ..Default::default()
    }
}

/// Renders one job and writes it as a partial EXR, read back as a merge would.
fn job(r: &Renderer, scene: &illum::scene::Scene, s: &RenderSettings, name: &str) -> Part {
    let out = r
        .render(scene, s, &mut |_, _| {})
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let path = temp_path(&format!("{name}.exr"));
    write_partial(&path, &part_info(scene, s, &out, "test"), &out.job.sums).unwrap();
    let (info, sums) = read_partial(&path).unwrap();
    assert_eq!(
        sums, out.job.sums,
        "{name}: the partial EXR reads back exactly"
    );
    Part { path, info, sums }
}

fn win(x0: u32, y0: u32, x1: u32, y1: u32) -> Window {
    Window { x0, y0, x1, y1 }
}

#[test]
fn split_renders_merge_bit_identical_to_one_render() {
    let ctx = context();
    let scene = scene(SCENE);
    let r = Renderer::new(ctx.clone());
    let mut traces = vec![TraceMode::Bvh];
    if ctx.ray_query() {
        traces.push(TraceMode::RayQuery);
    }
    for trace in traces {
        let whole = r
            .render(&scene, &settings(trace, 7, None, None), &mut |_, _| {})
            .unwrap();
        let t = format!("{trace:?}");
        // Sample ranges: unaligned ends, one inside a single block, one of whole blocks.
        let ranges = [(0, 100), (100, 130), (130, 512), (512, 600)];
        let parts: Vec<Part> = ranges
            .iter()
            .map(|&(a, b)| {
                job(
                    &r,
                    &scene,
                    &settings(trace, 7, Some((a, b)), None),
                    &format!("{t}-s{a}-{b}"),
                )
            })
            .collect();
        let merged = merge(&parts).unwrap();
        assert_eq!(
            merged.film, whole.film,
            "{t}: 4 sample ranges merged differ from one render"
        );
        assert_eq!(merged.spp, SPP);
        // Pixel windows of odd sizes.
        let tiles = [
            win(0, 0, 5, 4),
            win(5, 0, 13, 4),
            win(0, 4, 7, 9),
            win(7, 4, 13, 9),
        ];
        let parts: Vec<Part> = tiles
            .iter()
            .map(|w| {
                job(
                    &r,
                    &scene,
                    &settings(trace, 7, None, Some(*w)),
                    &format!("{t}-c{w}"),
                )
            })
            .collect();
        assert_eq!(
            merge(&parts).unwrap().film,
            whole.film,
            "{t}: 4 tiles merged differ from one render"
        );
        // Both at once: two tiles, each in two unaligned sample ranges.
        let mut parts = Vec::new();
        for w in [win(0, 0, 13, 5), win(0, 5, 13, 9)] {
            for (a, b) in [(0, 301), (301, 600)] {
                parts.push(job(
                    &r,
                    &scene,
                    &settings(trace, 7, Some((a, b)), Some(w)),
                    &format!("{t}-m{w}-{a}"),
                ));
            }
        }
        assert_eq!(
            merge(&parts).unwrap().film,
            whole.film,
            "{t}: tiles x ranges merged differ"
        );
    }
    assert_no_validation_messages(&ctx);
}

#[test]
fn merge_rejects_parts_that_do_not_belong_together() {
    let ctx = context();
    let scene = scene(SCENE);
    let r = Renderer::new(ctx.clone());
    let trace = TraceMode::Bvh;
    let part = |seed: u64, a: u32, b: u32, crop: Option<Window>, name: &str| {
        job(&r, &scene, &settings(trace, seed, Some((a, b)), crop), name)
    };
    let err = |parts: Vec<Part>| match merge(&parts) {
        Ok(_) => panic!("merged parts that do not belong together"),
        Err(e) => e.to_string(),
    };
    let expect = |msg: String, needles: &[&str]| {
        for n in needles {
            assert!(msg.contains(n), "{msg:?} lacks {n:?}");
        }
    };
    // Overlapping ranges name the part and illum.samples.
    let e = err(vec![
        part(1, 0, 400, None, "o1"),
        part(1, 300, 600, None, "o2"),
    ]);
    expect(e, &["o2.exr", "illum.samples", "overlaps"]);
    // A gap names the missing samples.
    let e = err(vec![
        part(1, 0, 200, None, "g1"),
        part(1, 300, 600, None, "g2"),
    ]);
    expect(e, &["samples 200..300", "missing"]);
    // Another seed.
    let e = err(vec![
        part(1, 0, 300, None, "s1"),
        part(2, 300, 600, None, "s2"),
    ]);
    expect(e, &["s2.exr", "illum.seed"]);
    // Another scene.
    let mut other = scene.clone();
    other.lights[0].intensity = 7.0;
    let p = job(
        &r,
        &other,
        &settings(trace, 1, Some((300, 600)), None),
        "scene2",
    );
    let e = err(vec![part(1, 0, 300, None, "scene1"), p]);
    expect(e, &["scene2.exr", "illum.sceneHash"]);
    // A part from another crop grid.
    let e = err(vec![
        part(1, 0, 600, Some(win(0, 0, 13, 5)), "grid1"),
        part(1, 0, 600, Some(win(0, 4, 13, 9)), "grid2"),
    ]);
    expect(e, &["grid2.exr", "illum.crop", "overlaps"]);
    // A missing tile.
    let e = err(vec![part(1, 0, 600, Some(win(0, 0, 13, 5)), "tile1")]);
    expect(e, &["cover", "missing"]);
    assert_no_validation_messages(&ctx);
}
