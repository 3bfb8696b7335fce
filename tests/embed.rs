//! Embedding: an application creates its own Vulkan instance and device, hands them to illum,
//! renders, and still owns (and destroys) them afterwards.

mod common;
use ash::vk;
use illum::render::{RenderSettings, Renderer};
use illum::vk::{Context, ExternalDevice};

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
                    spp: 2,
                    ..Default::default()
                },
                &mut |_, _| {},
            )
            .expect("render on the embedded device");
        assert_eq!(out.stats.trace, "bvh");
        assert!(out.film.beauty.iter().any(|p| p[0] > 0.0));
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
