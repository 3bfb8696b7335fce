//! A prepared scene: uploaded and built once, rendered many times with other seeds and
//! a moved camera, re-uploading nothing but the frame constants.

mod common;
use common::*;
use illum::layout::Frame;
use illum::render::{RenderSettings, Renderer};

const SCENE: &str = SMALL_SCENE;

fn settings(spp: u32) -> RenderSettings {
    RenderSettings {
        spp,
        trace: trace_mode(),
        ..Default::default()
    }
}

#[test]
fn a_prepared_scene_renders_again_uploading_only_its_frame_constants() {
    let ctx = context();
    let scene = scene(SCENE);
    let r = Renderer::new(ctx.clone());
    let prepared = r.prepare(&scene, trace_mode()).unwrap();
    r.loop_limited().unwrap(); // the driver probe, once per renderer, uploads its own buffer
    let kernels = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let k = kernels.clone();
    ctx.set_kernel_listener(Some(std::sync::Arc::new(move |e| {
        if let illum::vk::KernelEvent::Creating(_) = e {
            k.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        }
    })));
    let created = || kernels.load(std::sync::atomic::Ordering::SeqCst);
    let counts = || ctx.upload_counts();
    let before = counts();
    let a = r
        .render_prepared(&prepared, &scene.camera, &settings(8), &[1], &mut |_, _| {})
        .unwrap();
    let after_a = counts();
    let b = r
        .render_prepared(&prepared, &scene.camera, &settings(8), &[2], &mut |_, _| {})
        .unwrap();
    let after_b = counts();
    // Two renders, one kernel: the second reuses the pipeline the first created.
    assert_eq!(
        created(),
        1,
        "kernels created by two renders of the prepared scene"
    );
    let frame = std::mem::size_of::<Frame>() as u64;
    for (what, (n0, b0), (n1, b1)) in [("first", before, after_a), ("second", after_a, after_b)] {
        assert_eq!(
            (n1 - n0, b1 - b0),
            (1, frame),
            "{what} render of the prepared scene uploaded more than its frame"
        );
    }
    // The same images as renders of the scene itself.
    let fresh = r
        .render_seeds(&scene, &settings(8), &[1, 2], &mut |_, _| {})
        .unwrap();
    assert_eq!(a[0].film, fresh[0].film);
    assert_eq!(b[0].film, fresh[1].film);
    ctx.set_kernel_listener(None);
    assert_ne!(a[0].film.beauty, b[0].film.beauty);
    assert_no_validation_messages(&ctx);
}

fn rms_difference(a: &illum::output::Film, b: &illum::output::Film) -> f64 {
    let n = a.beauty.len() as f64;
    (a.beauty
        .iter()
        .zip(&b.beauty)
        .flat_map(|(p, q)| (0..3).map(move |c| (f64::from(p[c]) - f64::from(q[c])).powi(2)))
        .sum::<f64>()
        / (3.0 * n))
        .sqrt()
}

/// A moved camera (and another resolution) on the prepared scene gives the image of the scene
/// whose camera moved: the mean squared difference between the two is that of two renders of one
/// of them with other seeds (F-ratio over ~1700 values; 1.5 is far in the tail). The camera the
/// scene was prepared with gives a clearly different image (the test has power).
#[test]
fn a_moved_camera_renders_the_prepared_scene_as_a_fresh_one() {
    let ctx = context();
    let scene = scene(SCENE);
    let mut moved = scene.clone();
    moved.camera.position = glam::DVec3::new(-1.5, 1.6, 2.5);
    moved.camera.width = 24;
    moved.camera.height = 18;
    let r = Renderer::new(ctx.clone());
    let prepared = r.prepare(&scene, trace_mode()).unwrap();
    let s = settings(128);
    let p = r
        .render_prepared(&prepared, &moved.camera, &s, &[1, 2], &mut |_, _| {})
        .unwrap();
    let f = r.render_seeds(&moved, &s, &[3], &mut |_, _| {}).unwrap();
    assert_eq!((p[0].film.width, p[0].film.height), (24, 18));
    let noise = rms_difference(&p[0].film, &p[1].film);
    let same = rms_difference(&p[0].film, &f[0].film);
    let unmoved = r
        .render_prepared(
            &prepared,
            &{
                let mut c = scene.camera.clone();
                (c.width, c.height) = (24, 18);
                c
            },
            &s,
            &[4],
            &mut |_, _| {},
        )
        .unwrap();
    let other = rms_difference(&p[0].film, &unmoved[0].film);
    eprintln!(
        "rms: noise {noise:.4e}, moved camera vs fresh scene {same:.4e}, vs the unmoved camera {other:.4e}"
    );
    assert!(
        (same / noise).powi(2) < 1.5,
        "moved camera: {same} vs noise {noise}"
    );
    assert!(
        (other / noise).powi(2) > 3.0,
        "the unmoved camera should differ: {other} vs {noise}"
    );
    assert_no_validation_messages(&ctx);
}

/// A progressive render (`illum view`'s) stepped by uneven steps across a block boundary, moved
/// away and back in between, holds the blocking render's image bit for bit at every count: at
/// 100 of 300 samples the render at --spp 100, at the end the render at --spp 300 (film and exact
/// sums).
#[test]
fn a_progressive_render_is_the_blocking_render_at_every_count() {
    let ctx = context();
    let scene = scene(SCENE);
    let r = Renderer::new(ctx.clone());
    let prepared = r.prepare(&scene, trace_mode()).unwrap();
    let blocking = |spp| {
        r.render_prepared(
            &prepared,
            &scene.camera,
            &settings(spp),
            &[0],
            &mut |_, _| {},
        )
        .unwrap()
        .pop()
        .unwrap()
    };
    let (at_100, at_300) = (blocking(100), blocking(300));
    let mut p = r
        .progressive(&prepared, &scene.camera, &settings(300))
        .unwrap();
    let mut away = scene.camera.clone();
    away.position.x += 1.0;
    p.step(5).unwrap();
    p.restart(&away).unwrap();
    p.step(3).unwrap();
    p.restart(&scene.camera).unwrap();
    for step in [1, 3, 7, 64, 25] {
        p.step(step).unwrap();
    }
    assert_eq!(p.done(), 100);
    let mid = p.output().unwrap();
    assert_eq!(mid.film, at_100.film, "the image at 100 samples");
    assert_eq!(mid.stats.spp, 100);
    // The peek shown between steps is the same image, in f64.
    let peek = p.peek().unwrap();
    let b = illum::layout::FilmPixel::BEAUTY;
    for (i, px) in at_100.film.beauty.iter().enumerate() {
        let mean = peek.channel(i, b) / 100.0;
        assert!(
            (mean - f64::from(px[0])).abs() <= 1e-6 * mean.abs().max(1.0),
            "pixel {i}"
        );
    }
    while !p.finished() {
        p.step(37).unwrap();
    }
    let end = p.output().unwrap();
    assert_eq!(end.stats.spp, 300);
    assert!(!end.stats.interrupted);
    assert_eq!(end.film, at_300.film, "the image at 300 samples");
    assert_eq!(end.job, at_300.job, "the exact sums at 300 samples");
    assert_no_validation_messages(&ctx);
}
