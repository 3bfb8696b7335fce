//! Split renders: jobs by sample range (aligned to the film's 256-sample blocks or
//! not) and by pixel window, written as partial EXRs, read back and merged, give the render in
//! one piece bit for bit, on both trace paths; merging refuses parts that do not belong together,
//! naming the part and the field.

mod common;
use common::*;
use illum::film::Window;
use illum::jobs::{Part, merge, part_info};
use illum::render::{RenderSettings, Renderer};
use illum::trace::TraceMode;

/// Odd sizes everywhere: 13x9 pixels, 600 samples (blocks 0..256, 256..512, 512..600).
const SCENE: &str = SMALL_SCENE;
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
                render_part(
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
        let parts: Vec<Part> = ODD_TILES_13X9
            .iter()
            .map(|w| {
                render_part(
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
                parts.push(render_part(
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
        render_part(&r, &scene, &settings(trace, seed, Some((a, b)), crop), name)
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
    let p = render_part(
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
    expect(e, &["in no part", "missing"]);
    assert_no_validation_messages(&ctx);
}

/// The same through the command line: `illum render --samples`/`--crop` jobs merged by
/// `illum merge` give every channel of `illum render`'s EXR bit for bit, with the header's times
/// summed; a part given twice is refused, naming it.
#[test]
fn the_command_line_splits_and_merges_exactly() {
    let scene_path = temp_path("jobs-scene.json");
    std::fs::write(&scene_path, SCENE).unwrap();
    let scene = scene_path.to_str().unwrap();
    let path = |name: &str| temp_path(name).to_str().unwrap().to_owned();
    let common = ["--spp", "300", "--seed", "3", "--trace", "bvh", "--quiet"];
    let run = |extra: &[&str], out: &str| {
        let mut args = vec!["render", scene, "-o", out];
        args.extend_from_slice(&common);
        args.extend_from_slice(extra);
        let (code, err) = illum_cli(&args);
        assert_eq!(code, 0, "illum {args:?}:\n{err}");
    };
    let whole = path("cli-whole.exr");
    run(&[], &whole);
    let parts = [
        (path("cli-a.exr"), vec!["--samples", "0..170"]),
        (
            path("cli-b.exr"),
            vec!["--samples", "170..300", "--crop", "0,0,13,4"],
        ),
        (
            path("cli-c.exr"),
            vec!["--samples", "170..300", "--crop", "0,4,13,9"],
        ),
    ];
    for (out, extra) in &parts {
        run(extra, out);
    }
    let merged = path("cli-merged.exr");
    let mut args = vec!["merge", "-o", merged.as_str(), "--quiet"];
    args.extend(parts.iter().map(|p| p.0.as_str()));
    let (code, err) = illum_cli(&args);
    assert_eq!(code, 0, "illum merge:\n{err}");
    let a = illum::output::read_exr(std::path::Path::new(&whole)).unwrap();
    let b = illum::output::read_exr(std::path::Path::new(&merged)).unwrap();
    assert_eq!(a.channels.len(), b.channels.len());
    for ((na, va), (nb, vb)) in a.channels.iter().zip(&b.channels) {
        assert_eq!(na, nb);
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(va), bits(vb), "channel {na} differs after the merge");
    }
    assert_eq!(b.attribute("illum.spp"), Some("300"));
    let seconds = |img: &illum::output::ExrImage, name: &str| -> f64 {
        img.attribute(name).unwrap().parse().unwrap()
    };
    let parts_seconds: f64 = parts
        .iter()
        .map(|(p, _)| {
            let (info, _) = illum::jobs::partial::read_partial(std::path::Path::new(p)).unwrap();
            info.render_seconds
        })
        .sum();
    assert!((seconds(&b, "illum.renderSeconds") - parts_seconds).abs() < 1e-9);
    // The same part twice: refused, naming it and the field.
    let (code, err) = illum_cli(&[
        "merge",
        "-o",
        &path("cli-bad.exr"),
        &parts[0].0,
        &parts[0].0,
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("cli-a.exr") && err.contains("illum.samples"),
        "{err}"
    );
    // Parts a and b both rendered block 0..256 whole; a copy of b whose block differs at one
    // pixel and channel is refused, naming both files (the merge checks every shared block).
    let (info, mut sums) =
        illum::jobs::partial::read_partial(std::path::Path::new(&parts[1].0)).unwrap();
    let block = sums
        .boundary
        .iter_mut()
        .find(|b| b.start == 0)
        .expect("b shares block 0..256");
    block.sums[5 * illum::film::channels(0) + 1] += 1.0;
    let tampered = path("cli-b-tampered.exr");
    illum::jobs::partial::write_partial(std::path::Path::new(&tampered), &info, &sums).unwrap();
    let (code, err) = illum_cli(&[
        "merge",
        "-o",
        &path("cli-bad.exr"),
        &parts[0].0,
        &tampered,
        &parts[2].0,
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("cli-b-tampered.exr")
            && err.contains("cli-a.exr")
            && err.contains("samples 0..256 differ"),
        "{err}"
    );
}

/// An interrupted job has no part to write: its sums may hold part of a block it does not own.
#[test]
fn an_interrupted_job_writes_no_part() {
    let ctx = context();
    let scene = scene(SCENE);
    let r = Renderer::new(ctx.clone());
    let cancel = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(true));
    let s = RenderSettings {
        cancel: Some(cancel),
        ..settings(TraceMode::Bvh, 1, Some((100, 600)), None)
    };
    let out = r.render(&scene, &s, &mut |_, _| {}).unwrap();
    assert!(out.stats.interrupted);
    let e =
        part_info(&scene, &s, &out, "test").expect_err("an interrupted job must not make a part");
    assert!(e.to_string().contains("interrupted"), "{e}");
    assert_no_validation_messages(&ctx);
}

/// The memory limit under which `settings`' render of a `width` x `height` frame takes bands
/// of `rows` rows (src/render/bands.rs): the process, the frame's planes and one band's film.
fn limit_for_bands(settings: &RenderSettings, width: u32, height: u32, rows: u32) -> u64 {
    use illum::film::memory;
    let planes = settings.integrator.aov_planes().len();
    let ring = if settings.adaptive.is_some() { 2 } else { 0 };
    let pixels = u64::from(width) * u64::from(height);
    memory::PROCESS_BYTES
        + pixels * memory::frame_bytes_per_pixel(planes)
        + u64::from(rows + ring) * u64::from(width) * memory::bytes_per_pixel(planes, false, false)
}

/// A frame whose film does not fit the memory budget renders in bands of rows in turn, each the
/// crop it is: every plane bit for bit as the frame rendered whole, with the direct integrator,
/// with `full` (its radiosity cache spans the frame) and with adaptive sampling (its pilot takes
/// a ring of rows around each band). Cancelled after the first band, the rows rendered are kept
/// and the rest say they took no sample.
#[test]
fn a_frame_too_large_for_the_memory_renders_in_bands_bit_identical() {
    use illum::render::adaptive::Adaptive;
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    let ctx = context();
    let mut scene = scene(SCENE);
    (scene.camera.width, scene.camera.height) = (24, 40);
    let r = Renderer::new(ctx.clone());
    let params = illum::render::Params::new();
    let cases = [
        ("direct", None),
        ("full", None),
        ("direct", Some(Adaptive::threshold(0.05, 4))),
    ];
    for (name, adaptive) in cases {
        let whole = RenderSettings {
            integrator: illum::integrators::create(name, &params).unwrap(),
            spp: 24,
            seed: 5,
            adaptive,
            ..Default::default()
        };
        let banded = RenderSettings {
            memory_limit: Some(limit_for_bands(&whole, 24, 40, 16)),
            ..whole.clone()
        };
        let a = r.render(&scene, &whole, &mut |_, _| {}).unwrap();
        let b = r.render(&scene, &banded, &mut |_, _| {}).unwrap();
        let bands = b.stats.bands.expect("rendered in bands");
        assert_eq!((bands.count, bands.rows, bands.done), (3, 16, 3), "{name}");
        assert!(a.stats.bands.is_none() && b.job.is_none() && b.sums().is_err());
        assert_eq!(
            a.film, b.film,
            "{name} {adaptive:?}: bands differ from the whole frame"
        );
        assert_eq!(a.stats.camera_samples, b.stats.camera_samples, "{name}");
        assert_eq!(a.stats.rays, b.stats.rays, "{name}");
        // One byte less and no band of 16 rows fits: refused, as the whole frame is.
        let short = RenderSettings {
            memory_limit: Some(limit_for_bands(&whole, 24, 40, 16) - 1),
            ..whole.clone()
        };
        let s = r.render(&scene, &short, &mut |_, _| {});
        assert!(s.is_err(), "{name}: rendered under a limit it cannot fit");
    }

    // Cancelled once the first band is done: its rows are the whole frame's, the others empty.
    let cancel = Arc::new(AtomicBool::new(false));
    let whole = RenderSettings {
        integrator: illum::integrators::create("direct", &params).unwrap(),
        spp: 24,
        seed: 5,
        ..Default::default()
    };
    let banded = RenderSettings {
        memory_limit: Some(limit_for_bands(&whole, 24, 40, 16)),
        cancel: Some(cancel.clone()),
        ..whole.clone()
    };
    let a = r.render(&scene, &whole, &mut |_, _| {}).unwrap();
    let flag = cancel.clone();
    let b = r
        .render(&scene, &banded, &mut |done, budget| {
            if done * 3 >= budget && done > 0 {
                flag.store(true, Ordering::Relaxed);
            }
        })
        .unwrap();
    let bands = b.stats.bands.unwrap();
    assert!(b.stats.interrupted && bands.done == 1, "{bands:?}");
    let first = 16 * 24;
    assert_eq!(&b.film.beauty[..first], &a.film.beauty[..first]);
    assert!(b.film.beauty[first..].iter().all(|p| *p == [0.0; 3]));
    let samples = b.film.samples.as_ref().expect("a SampleCount plane");
    assert!(samples[..first].iter().all(|&s| s == 24.0));
    assert!(samples[first..].iter().all(|&s| s == 0.0));
    assert_no_validation_messages(&ctx);
}
