//! Embedding: an application creates its own Vulkan instance and device, hands them to illum,
//! renders, and still owns (and destroys) them afterwards.

#[path = "embed/app.rs"]
mod app;
mod common;
#[path = "embed/host.rs"]
mod host;
use app::App;
use ash::vk;
use illum::render::{Pass, PreparedScene, RenderSettings, Renderer};
use illum::trace::TraceMode;

const SPP: u32 = 4096;

/// The fraction of pixel (x, y) whose box filter sees the unit sphere at the origin, by
/// `s` × `s` stratified positions (the camera rays of `primary.comp`).
fn coverage(cam: &illum::scene::Camera, x: u32, y: u32, s: u32) -> f64 {
    let forward = (cam.look_at - cam.position).normalize();
    let right = forward.cross(cam.up).normalize();
    let up = right.cross(forward);
    let tan_half = (cam.fov_y_deg.to_radians() * 0.5).tan();
    let aspect = f64::from(cam.width) / f64::from(cam.height);
    let mut hits = 0u32;
    for j in 0..s {
        for i in 0..s {
            let u = (f64::from(x) + (f64::from(i) + 0.5) / f64::from(s)) / f64::from(cam.width);
            let v = (f64::from(y) + (f64::from(j) + 0.5) / f64::from(s)) / f64::from(cam.height);
            let d = (forward + (2.0 * u - 1.0) * tan_half * aspect * right
                - (2.0 * v - 1.0) * tan_half * up)
                .normalize();
            // |o + t d| = 1 has a root iff the ray passes within 1 of the centre.
            let b = cam.position.dot(d);
            if cam.position.length_squared() - b * b < 1.0 {
                hits += 1;
            }
        }
    }
    f64::from(hits) / f64::from(s * s)
}

/// A diffuse sphere (albedo ρ = 0.5) under a constant white dome (L = 1), direct lighting only:
/// the sphere is convex, so every point sees the whole dome over its horizon and reflects exactly
/// ρ L = 0.5; the background is the visible dome, exactly 1; a pixel on the outline covering a
/// fraction c of sphere expects 1 − 0.5 c. The sample variance σ² of one sample on the sphere is
/// estimated from the spread of the pixels entirely on it (independent pixels of one expected
/// value), not from the Variance AOV; an outline pixel adds the Bernoulli variance of which
/// surface a sample sees, c (1 − c) (1 − 0.5)². Each pixel is t-tested (Šidák at 1e-3). The
/// constant dome's light samples follow the cosine about the normal, so that each sample on the
/// sphere is ρ L exactly (σ = 0) where diffuse light samples alone light it: then the pixels on
/// the sphere must be 0.5 to float precision.
fn check_sphere_under_dome(cam: &illum::scene::Camera, beauty: &[[f32; 3]]) {
    let w = cam.width;
    let cover: Vec<(f64, f64)> = (0..beauty.len() as u32)
        .map(|i| {
            let (c, fine) = (
                coverage(cam, i % w, i / w, 32),
                coverage(cam, i % w, i / w, 64),
            );
            (fine, (fine - c).abs())
        })
        .collect();
    let inside: Vec<f64> = beauty
        .iter()
        .zip(&cover)
        .filter(|(_, c)| c.0 == 1.0 && c.1 == 0.0)
        .map(|(p, _)| f64::from(p[0]))
        .collect();
    let outside = cover.iter().filter(|c| c.0 == 0.0 && c.1 == 0.0).count();
    assert!(
        inside.len() >= 20 && outside >= 10,
        "{} pixels on the sphere, {outside} off it",
        inside.len()
    );
    let k = inside.len() as f64;
    let mean = inside.iter().sum::<f64>() / k;
    // Variance of one pixel mean on the sphere, then of one sample.
    let var_pixel = inside.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (k - 1.0);
    let sigma2 = var_pixel * f64::from(SPP);
    eprintln!(
        "sphere pixels: mean {mean:.5} (expected 0.5), sample σ {:.4}",
        sigma2.sqrt()
    );
    let per = 1.0 - (1.0 - 1e-3f64).powf(1.0 / (beauty.len() * 3 + 1) as f64);
    let t = common::t_for(per, k - 1.0);
    if var_pixel > 0.0 {
        let tm = (mean - 0.5) / (var_pixel / k).sqrt();
        assert!(
            tm.abs() <= t,
            "mean over the sphere {mean} vs 0.5: t = {tm:.2}"
        );
    } else {
        assert!(
            (mean - 0.5).abs() < 1e-6,
            "every pixel on the sphere is {mean}, not 0.5"
        );
    }
    for (i, (p, &(c, c_err))) in beauty.iter().zip(&cover).enumerate() {
        let expected = 1.0 - 0.5 * c;
        let se = ((c * sigma2 + c * (1.0 - c) * 0.25) / f64::from(SPP)).sqrt();
        for (ch, &value) in p.iter().enumerate() {
            let d = f64::from(value) - expected;
            let tol = t * se + 0.5 * c_err + 1e-6;
            assert!(
                d.abs() <= tol,
                "pixel ({}, {}) channel {ch}: {value} vs {expected} (coverage {c}) ± {tol}",
                i as u32 % w,
                i as u32 / w
            );
        }
    }
}

const SPHERE_UNDER_DOME: &str = r#"{"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_y": 40, "resolution": [12, 8]},
    "materials": {"m": {"diffuse": [0.5, 0.5, 0.5]}},
    "shapes": {"s": {"sphere": {"center": [0, 0, 0], "radius": 1}, "material": "m"}},
    "lights": {"sky": {"dome": {}, "color": [1, 1, 1]}}}"#;

/// Renders the sphere under the dome on `ctx` with `trace`, checks the image, drops the context,
/// then uses and destroys the application's device: it is still the application's.
fn render_and_release(ctx: illum::vk::Context, device: ash::Device, trace: TraceMode) {
    let scene = common::scene(SPHERE_UNDER_DOME);
    let mut out = Renderer::new(ctx.clone())
        .render(
            &scene,
            &RenderSettings {
                spp: SPP,
                trace,
                ..Default::default()
            },
            &mut |_, _| {},
        )
        .expect("render on the embedded device");
    let (traced, beauty) = (out.stats.trace, std::mem::take(&mut out.film.beauty));
    drop(out);
    drop(ctx);
    // SAFETY: illum's context is gone; the device is the application's to use and destroy.
    unsafe {
        device
            .device_wait_idle()
            .expect("device still alive after illum is dropped");
        let fence = device
            .create_fence(&vk::FenceCreateInfo::default(), None)
            .expect("still usable");
        device.destroy_fence(fence, None);
        device.destroy_device(None);
    }
    // Checked once the device is gone: a failed check must not leave it alive (the process
    // then crashed at exit, hiding the other tests' results).
    assert_eq!(
        traced,
        if trace == TraceMode::RayQuery {
            "rayquery"
        } else {
            "bvh"
        }
    );
    check_sphere_under_dome(&scene.camera, &beauty);
}

/// Records samples [first, first + count) into the host's frame command buffer `cmd`.
fn record(
    session: &mut illum::render::RenderSession,
    cmd: vk::CommandBuffer,
    first: u32,
    count: u32,
) {
    // SAFETY: the host's command buffer is recording, outside its render pass; the frame waits
    // for it before the session goes.
    unsafe {
        session.record_pass(
            cmd,
            &Pass {
                first_sample: first,
                sample_count: count,
            },
        )
    }
    .unwrap()
}

#[test]
fn renders_on_an_application_device_without_ray_queries() {
    let app = App::new();
    // The application enables illum's base set only: illum must then trace with its compute BVH
    // even if the device could do ray queries.
    let (device, ctx) = app.device(&app.requirements().base);
    let ctx = ctx.expect("wrapping the application's device");
    assert!(!ctx.ray_query());
    render_and_release(ctx, device, TraceMode::Auto);
    app.assert_silent();
}

#[test]
fn renders_on_an_application_device_with_ray_queries() {
    let app = App::new();
    let req = app.requirements();
    let Some(rq) = req.ray_query.clone() else {
        // Mesa 22's lavapipe: no ray queries, and saying they were enabled is refused.
        let mut claimed = req.base.clone();
        claimed.ray_query.ray_query = vk::TRUE;
        let (device, ctx) = app.device(&req.base);
        // SAFETY: the device is valid; the context is refused, and the device destroyed after.
        let err = unsafe { app.wrap(&device, claimed, app.queue_family) }
            .err()
            .expect("ray queries the device lacks must be refused")
            .to_string();
        assert!(err.contains("does not offer"), "{err}");
        drop(ctx);
        // SAFETY: no context holds the device any more.
        unsafe { device.destroy_device(None) };
        return;
    };
    let (device, ctx) = app.device(&rq);
    let ctx = ctx.expect("wrapping the application's ray-query device");
    assert!(ctx.ray_query());
    render_and_release(ctx, device, TraceMode::RayQuery);
    app.assert_silent();
}

#[test]
fn from_external_names_what_the_device_lacks() {
    let app = App::new();
    let req = app.requirements();
    assert!(req.missing.is_empty(), "{:?}", req.missing);
    let base = &req.base;
    assert_eq!(base.vulkan12.buffer_device_address, vk::TRUE);
    assert_eq!(base.vulkan12.scalar_block_layout, vk::TRUE);
    assert_eq!(base.features.shader_int64, vk::TRUE);
    assert!(base.extensions.is_empty() && !base.has_ray_query());
    if let Some(rq) = &req.ray_query {
        let names: Vec<_> = rq.extensions.iter().map(|e| e.to_str().unwrap()).collect();
        assert!(names.contains(&"VK_KHR_ray_query"), "{names:?}");
        assert!(
            names.contains(&"VK_KHR_acceleration_structure"),
            "{names:?}"
        );
    }
    // A device created without scalarBlockLayout: the error names the feature.
    let mut without = base.clone();
    without.vulkan12.scalar_block_layout = vk::FALSE;
    let (device, ctx) = app.device(&without);
    let err = ctx
        .err()
        .expect("a device without scalarBlockLayout")
        .to_string();
    assert!(
        err.contains("VkPhysicalDeviceVulkan12Features::scalarBlockLayout"),
        "{err}"
    );
    assert!(!err.contains("bufferDeviceAddress"), "{err}");
    // A queue family that does not exist.
    // SAFETY: the device is valid; the context is refused.
    let err = unsafe { app.wrap(&device, base.clone(), 99) }
        .err()
        .expect("queue family 99")
        .to_string();
    assert!(err.contains("queue_family_index 99"), "{err}");
    // SAFETY: no context holds the device.
    unsafe { device.destroy_device(None) };
    app.assert_silent();
}

/// `record_pass` in the host's frame loop (its render pass, then illum's pass, then its copy of
/// the image, in one command buffer per frame), under synchronization validation: the image after
/// each pass is the blocking render's of as many samples, bit for bit, and after a camera move the
/// moved camera's.
#[test]
fn record_pass_in_a_host_frame_equals_the_render_bit_for_bit() {
    let app = App::new();
    let (device, ctx) = app.device(&app.requirements().base);
    let ctx = ctx.expect("the application's device");
    let scene = common::scene(common::SMALL_SCENE);
    let (w, h) = (scene.camera.width, scene.camera.height);
    let r = Renderer::new(ctx.clone());
    let settings = RenderSettings {
        spp: 8,
        seed: 7,
        ..Default::default()
    };
    let mut prepared = r.prepare(&scene, TraceMode::Auto).unwrap();
    let render = |p: &PreparedScene, camera: &illum::scene::Camera, spp: u32| {
        let s = RenderSettings {
            spp,
            ..settings.clone()
        };
        r.render_prepared(p, camera, &s, &[7], &mut |_, _| {})
            .unwrap()
            .remove(0)
            .film
            .beauty
    };
    let mut moved = scene.camera.clone();
    moved.position = glam::DVec3::new(-0.8, 1.5, 2.6);
    let refs = [
        render(&prepared, &scene.camera, 1),
        render(&prepared, &scene.camera, 3),
        render(&prepared, &scene.camera, 8),
        render(&prepared, &moved, 8),
    ];
    // The prepared scene renders as the scene file does.
    let file = r.render(&scene, &settings, &mut |_, _| {}).unwrap();
    assert!(file.film.beauty == refs[2]);
    // SAFETY: the host's objects are destroyed below, before the device.
    let host =
        unsafe { host::HostFrame::new(&app.instance, app.pd, &device, app.queue_family, [w, h]) };
    let images = {
        let mut session = r
            .session(&mut prepared, &scene.camera, &settings, host.target())
            .unwrap();
        let pass = |session: &mut illum::render::RenderSession, first, count| {
            host.frame(|cmd| record(session, cmd, first, count))
        };
        let mut images = vec![
            pass(&mut session, 0, 1),
            pass(&mut session, 1, 2),
            pass(&mut session, 3, 5),
        ];
        session.set_camera(&moved).unwrap();
        images.push(pass(&mut session, 0, 8));
        assert_eq!(session.samples(), 8);
        // A pass that does not follow the last one is refused before anything is recorded.
        // SAFETY: refused before the command buffer is touched.
        let e = unsafe {
            session.record_pass(
                host.cmd,
                &Pass {
                    first_sample: 3,
                    sample_count: 1,
                },
            )
        }
        .unwrap_err()
        .to_string();
        assert!(e.contains("where the previous pass ended (8)"), "{e}");
        images
    };
    for (k, (image, reference)) in images.iter().zip(&refs).enumerate() {
        assert_eq!(image.len(), reference.len());
        for (i, (p, q)) in image.iter().zip(reference).enumerate() {
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(
                bits(&p[..3]),
                bits(q),
                "image {k}, pixel {i}: {p:?} vs {q:?}"
            );
            assert_eq!(p[3], 1.0);
        }
    }
    assert!(
        refs[0] != refs[2] && refs[2] != refs[3],
        "the references differ"
    );
    host.destroy();
    drop(prepared);
    drop(r);
    drop(file);
    drop(ctx);
    // SAFETY: illum's context is gone.
    unsafe { device.destroy_device(None) };
    app.assert_silent();
}

/// Bit-for-bit equality of a host image's RGB with a reference, and alpha 1.
fn assert_same_bits(what: &str, image: &[[f32; 4]], reference: &[[f32; 3]]) {
    assert_eq!(image.len(), reference.len(), "{what}");
    for (i, (p, q)) in image.iter().zip(reference).enumerate() {
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&p[..3]), bits(q), "{what}, pixel {i}: {p:?} vs {q:?}");
        assert_eq!(p[3], 1.0, "{what}, pixel {i}");
    }
}

/// Sessions of the integrators with AOV planes (`path`, `full`), in the host's frame under
/// synchronization validation: the beauty and every AOV image equal the blocking render's beauty
/// and AOV planes bit for bit, `full` against the render with `radiosity_refresh` off (its cache
/// warmed once, see src/render/session.rs), also after a camera move and `refresh_cache`.
#[test]
fn sessions_with_aov_planes_equal_the_render_bit_for_bit() {
    use illum::integrators::{Full, Path};
    use illum::render::Integrator;
    use std::sync::Arc;
    let app = App::new();
    // Ray queries where the driver has them: the integrators' kernels compile faster there.
    let req = app.requirements();
    let (device, ctx) = app.device(req.ray_query.as_ref().unwrap_or(&req.base));
    let ctx = ctx.expect("the application's device");
    let scene = common::scene(common::SMALL_SCENE);
    let (w, h) = (scene.camera.width, scene.camera.height);
    let r = Renderer::new(ctx.clone());
    let mut moved = scene.camera.clone();
    moved.position = glam::DVec3::new(-0.8, 1.5, 2.6);
    let mut edited = scene.clone();
    edited.camera = moved.clone();
    let ball = edited.materials.iter_mut().find(|m| m.name == "ball");
    ball.unwrap().diffuse = glam::Vec3::new(0.2, 0.6, 0.3);
    // SAFETY: the host's objects are destroyed below, before the device.
    let host = unsafe {
        host::HostFrame::with_images(&app.instance, app.pd, &device, app.queue_family, [w, h], 4)
    };
    let path: Arc<dyn Integrator> = Path::default().into();
    let full: Arc<dyn Integrator> = Full {
        radiosity_refresh: false,
        ..Default::default()
    }
    .into();
    for integrator in [path, full] {
        let kind = integrator.name();
        let settings = RenderSettings {
            spp: 4,
            seed: 11,
            integrator,
            ..Default::default()
        };
        let mut prepared = r.prepare(&scene, TraceMode::Auto).unwrap();
        let render = |p: &PreparedScene, camera: &illum::scene::Camera, s: &RenderSettings| {
            r.render_prepared(p, camera, s, &[11], &mut |_, _| {})
                .unwrap()
                .remove(0)
                .film
        };
        let one = RenderSettings {
            spp: 1,
            ..settings.clone()
        };
        let refs = [
            render(&prepared, &scene.camera, &one),
            render(&prepared, &scene.camera, &settings),
            render(&prepared, &moved, &settings),
        ];
        let planes: Vec<&str> = refs[0].aovs.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(planes, ["Direct", "IndirectDiffuse", "Reflection"]);
        if kind == "full" {
            // The setting matters: generations during the render change the image.
            let mut on = settings.clone();
            on.integrator = Full::default().into();
            assert!(render(&prepared, &scene.camera, &on).beauty != refs[1].beauty);
        }
        let images = {
            let mut session = r
                .session(&mut prepared, &scene.camera, &settings, host.target())
                .unwrap();
            assert_eq!(session.aov_planes(), &planes[..]);
            let e = session
                .add_aov_target("Albedo", host.target_at(1))
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("\"Albedo\"") && e.contains("Direct, IndirectDiffuse, Reflection"),
                "{e}"
            );
            for (k, plane) in planes.iter().enumerate() {
                session
                    .add_aov_target(plane, host.target_at(k + 1))
                    .unwrap();
            }
            let pass = |session: &mut illum::render::RenderSession, first, count| {
                host.frame_all(|cmd| record(session, cmd, first, count))
            };
            let mut images = vec![pass(&mut session, 0, 1), pass(&mut session, 1, 3)];
            session.set_camera(&moved).unwrap();
            session.refresh_cache().unwrap();
            images.push(pass(&mut session, 0, 4));
            // A material edit: `full` warms its cache up again.
            session.update_scene(&edited).unwrap();
            images.push(pass(&mut session, 0, 4));
            images
        };
        // The prepared scene now holds the edit.
        let mut refs = Vec::from(refs);
        refs.push(render(&prepared, &moved, &settings));
        for (k, (image, reference)) in images.iter().zip(&refs).enumerate() {
            let what = format!("{} image {k}", kind);
            assert_same_bits(&format!("{what} beauty"), &image[0], &reference.beauty);
            for (p, plane) in reference.aovs.iter().enumerate() {
                assert_same_bits(&format!("{what} {}", plane.name), &image[p + 1], &plane.rgb);
            }
        }
        assert_eq!(images.len(), 4);
        assert!(
            refs[0].beauty != refs[1].beauty
                && refs[1].beauty != refs[2].beauty
                && refs[2].beauty != refs[3].beauty
        );
    }
    host.destroy();
    drop(r);
    drop(ctx);
    // SAFETY: illum's context is gone.
    unsafe { device.destroy_device(None) };
    app.assert_silent();
}
