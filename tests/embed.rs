//! Embedding: an application creates its own Vulkan instance and device, hands them to illum,
//! renders, and still owns (and destroys) them afterwards.

mod common;
use ash::vk;
use illum::render::{RenderSettings, Renderer};
use illum::vk::{Context, ExternalDevice};

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
/// surface a sample sees, c (1 − c) (1 − 0.5)². Each pixel is t-tested (Šidák at 1e-3).
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
    assert!(
        var_pixel > 0.0,
        "the pixels on the sphere cannot all be equal"
    );
    let per = 1.0 - (1.0 - 1e-3f64).powf(1.0 / (beauty.len() * 3 + 1) as f64);
    let t = common::t_for(per, k - 1.0);
    let tm = (mean - 0.5) / (var_pixel / k).sqrt();
    assert!(
        tm.abs() <= t,
        "mean over the sphere {mean} vs 0.5: t = {tm:.2}"
    );
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

#[test]
fn renders_on_an_application_device_and_leaves_it_alive() {
    // SAFETY: plain Vulkan setup of the "application"; every object is destroyed at the end.
    unsafe {
        let entry = ash::Entry::load().expect("Vulkan loader");
        let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_2);
        let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
        let instance = entry
            .create_instance(
                &vk::InstanceCreateInfo::default()
                    .application_info(&app)
                    .enabled_layer_names(&layers),
                None,
            )
            .expect("instance");
        let pd = instance.enumerate_physical_devices().unwrap()[0];
        let qf = instance
            .get_physical_device_queue_family_properties(pd)
            .iter()
            .position(|q| q.queue_flags.contains(vk::QueueFlags::COMPUTE))
            .unwrap() as u32;
        // The application enables what illum needs, without ray queries: illum must then trace
        // with its compute BVH even if the device could do ray queries.
        let mut f12 = vk::PhysicalDeviceVulkan12Features::default()
            .buffer_device_address(true)
            .scalar_block_layout(true);
        let mut f2 = vk::PhysicalDeviceFeatures2::default()
            .features(vk::PhysicalDeviceFeatures::default().shader_int64(true))
            .push_next(&mut f12);
        let prio = [1.0f32];
        let qi = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(qf)
            .queue_priorities(&prio)];
        let device = instance
            .create_device(
                pd,
                &vk::DeviceCreateInfo::default()
                    .queue_create_infos(&qi)
                    .push_next(&mut f2),
                None,
            )
            .expect("device");
        let queue = device.get_device_queue(qf, 0);
        let ctx = Context::from_external(ExternalDevice {
            entry: entry.clone(),
            instance: instance.clone(),
            physical_device: pd,
            device: device.clone(),
            queue,
            queue_family_index: qf,
            ray_query_enabled: false,
        })
        .expect("wrapping the application's device");
        assert!(!ctx.ray_query());
        let scene = common::scene(
            r#"{"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_y": 40, "resolution": [12, 8]},
                "materials": {"m": {"diffuse": [0.5, 0.5, 0.5]}},
                "shapes": {"s": {"sphere": {"center": [0, 0, 0], "radius": 1}, "material": "m"}},
                "lights": {"sky": {"dome": {}, "color": [1, 1, 1]}}}"#,
        );
        let out = Renderer::new(ctx.clone())
            .render(
                &scene,
                &RenderSettings {
                    spp: SPP,
                    ..Default::default()
                },
                &mut |_, _| {},
            )
            .expect("render on the embedded device");
        assert_eq!(out.stats.trace, "bvh");
        check_sphere_under_dome(&scene.camera, &out.film.beauty);
        drop(out);
        drop(ctx);
        // The device is still the application's: it can still be used, then destroyed by it.
        device
            .device_wait_idle()
            .expect("device still alive after illum is dropped");
        let fence = device
            .create_fence(&vk::FenceCreateInfo::default(), None)
            .expect("still usable");
        device.destroy_fence(fence, None);
        device.destroy_device(None);
        instance.destroy_instance(None);
    }
}
