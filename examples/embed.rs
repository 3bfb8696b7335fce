//! Embedding illum in an application's Vulkan frame: the application creates its own
//! instance and a device with what `illum::vk::requirements` asks for, builds a scene in code,
//! and renders 10 progressive passes into its own storage image while orbiting the camera (a new
//! viewpoint every second pass, which restarts the accumulation), recording each pass into its own
//! command buffer; it reads the image back and writes it as a PNG, printing the time of each pass
//! and of each update.
//!
//! `cargo run --release --example embed [OUT.png]` (default embed.png). `ILLUM_VALIDATION=1`
//! turns the validation layers on (with synchronization validation; they print what they find).

use ash::vk;
use illum::render::{ImageState, Pass, RenderSettings, Renderer, TargetImage};
use illum::scene::SceneBuilder;
use illum::scene::format::*;
use illum::vk::{Context, ExternalDevice};
use std::time::Instant;

const W: u32 = 160;
const H: u32 = 120;

fn main() -> anyhow::Result<()> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "embed.png".into());
    let validate = std::env::var("ILLUM_VALIDATION").is_ok_and(|v| v == "1");
    // SAFETY: plain Vulkan set-up; every object is destroyed at the end, illum's context first.
    unsafe {
        // The application's instance and device.
        let entry = ash::Entry::load()?;
        let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_2);
        let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
        let sync = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut vf = vk::ValidationFeaturesEXT::default().enabled_validation_features(&sync);
        let mut ici = vk::InstanceCreateInfo::default().application_info(&app);
        if validate {
            ici = ici.enabled_layer_names(&layers).push_next(&mut vf);
        }
        let instance = entry.create_instance(&ici, None)?;
        let pd = instance.enumerate_physical_devices()?[0];
        let req = illum::vk::requirements(&instance, pd)?;
        anyhow::ensure!(req.missing.is_empty(), "the device lacks {:?}", req.missing);
        // Ray queries where the device has them, else illum's compute BVH.
        let set = req.ray_query.clone().unwrap_or_else(|| req.base.clone());
        let qf = req.queue_family.expect("a compute queue");
        let device = set.create_device(&instance, pd, qf)?;
        let queue = device.get_device_queue(qf, 0);
        let ctx = Context::from_external(ExternalDevice {
            entry: entry.clone(),
            instance: instance.clone(),
            physical_device: pd,
            device: device.clone(),
            queue,
            queue_family_index: qf,
            enabled: set,
        })?;
        println!(
            "device: {} (ray queries {})",
            ctx.info().name,
            if ctx.ray_query() { "on" } else { "off" }
        );

        // A scene built in code: a floor, a ball, a mesh from host slices, a key light and a sky.
        let mut scene = build_scene()?;
        let renderer = Renderer::new(ctx.clone());
        let t = Instant::now();
        let mut prepared = renderer.prepare(&scene, Default::default())?;
        println!(
            "prepare: {:.1} ms ({})",
            t.elapsed().as_secs_f64() * 1e3,
            prepared.trace_name()
        );

        // The application's storage image, read-back buffer, command buffer and fence.
        let host = Host::new(&instance, pd, &device, qf)?;
        let settings = RenderSettings {
            seed: 1,
            ..Default::default()
        };
        let mut session =
            renderer.session(&mut prepared, &scene.camera, &settings, host.target())?;
        for pass in 0..10u32 {
            if pass % 2 == 0 {
                // Orbit: a new viewpoint, and the ball's colour follows the angle.
                let angle = f64::from(pass / 2) * 0.35;
                scene.camera.position = glam::DVec3::new(3.2 * angle.sin(), 1.3, 3.2 * angle.cos());
                let t = Instant::now();
                session.set_camera(&scene.camera)?;
                let camera_ms = t.elapsed().as_secs_f64() * 1e3;
                scene.materials[1].diffuse = glam::Vec3::new(0.7, 0.3 + 0.1 * angle as f32, 0.2);
                let t = Instant::now();
                let u = session.update_scene(&scene)?;
                println!(
                    "update: camera {camera_ms:.3} ms, material {:.3} ms ({:?} written)",
                    t.elapsed().as_secs_f64() * 1e3,
                    u.tables
                );
            }
            let p = if pass % 2 == 0 {
                Pass {
                    first_sample: 0,
                    sample_count: 4,
                }
            } else {
                Pass {
                    first_sample: 4,
                    sample_count: 12,
                }
            };
            let t = Instant::now();
            host.frame(|cmd| session.record_pass(cmd, &p))?;
            println!(
                "pass {pass}: samples [{}, {}) in {:.1} ms (record, submit, wait, read back)",
                p.first_sample,
                p.first_sample + p.sample_count,
                t.elapsed().as_secs_f64() * 1e3
            );
        }
        drop(session);
        // The blocking render of the same prepared scene, for comparison with the passes.
        for spp in [4, 16] {
            let s = RenderSettings {
                spp,
                ..settings.clone()
            };
            let t = Instant::now();
            renderer.render_prepared(&prepared, &scene.camera, &s, &[1], &mut |_, _| {})?;
            println!(
                "render_prepared (blocking) of {spp} samples: {:.1} ms",
                t.elapsed().as_secs_f64() * 1e3
            );
        }
        let texels = host.read();
        let mut film = illum::output::Film::new(W, H);
        for (dst, t) in film.beauty.iter_mut().zip(&texels) {
            *dst = [t[0], t[1], t[2]];
        }
        illum::output::write_png(std::path::Path::new(&out), &film)?;
        println!("wrote {out}");
        host.destroy();
        drop(prepared);
        drop(renderer);
        drop(ctx);
        device.destroy_device(None);
        instance.destroy_instance(None);
    }
    Ok(())
}

fn build_scene() -> anyhow::Result<illum::scene::Scene> {
    let mut b = SceneBuilder::new(CameraDef::look_at(
        [0.0, 1.3, 3.2],
        [0.0, 0.4, 0.0],
        40.0,
        [W, H],
    ));
    let card = [
        [-0.4, 0.0, 0.0],
        [0.4, 0.0, 0.0],
        [0.4, 0.8, 0.0],
        [-0.4, 0.8, 0.0],
    ];
    b.material(
        "floor",
        MaterialDef {
            diffuse: [0.6, 0.6, 0.6],
            ..Default::default()
        },
    )
    .material(
        "ball",
        MaterialDef {
            diffuse: [0.7, 0.3, 0.2],
            specular: vec![LobeDef {
                model: ModelDef::Ggx,
                roughness: NumOrArray::One(0.2),
                fresnel: default_fresnel(),
            }],
            ..Default::default()
        },
    )
    .material(
        "card",
        MaterialDef {
            diffuse: [0.2, 0.5, 0.7],
            two_sided: true,
            ..Default::default()
        },
    )
    .shape(
        "floor",
        ShapeDef::rect([0.0; 3], [0.0, 1.0, 0.0], [6.0, 6.0], "floor"),
    )
    .shape("ball", ShapeDef::sphere([0.0, 0.5, 0.0], 0.5, "ball"))
    .mesh(
        "card",
        "card",
        &card,
        &[0, 1, 2, 0, 2, 3],
        Some(TransformDef {
            translate: Some([-0.9, 0.0, -0.3]),
            rotate: Some([0.0, 30.0, 0.0]),
            ..Default::default()
        }),
    )
    .light(
        "key",
        LightDef::rect([1.0, 2.0, 1.0], [-0.4, -1.0, -0.4], [0.8, 0.8], 6.0),
    )
    .light("sky", LightDef::dome([0.2, 0.3, 0.4]));
    Ok(b.build()?)
}

/// The application's side: its storage image for illum, a read-back buffer, a command buffer.
struct Host {
    device: ash::Device,
    image: vk::Image,
    view: vk::ImageView,
    buffer: vk::Buffer,
    memory: [vk::DeviceMemory; 2],
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    queue: vk::Queue,
}

impl Host {
    unsafe fn new(
        instance: &ash::Instance,
        pd: vk::PhysicalDevice,
        device: &ash::Device,
        qf: u32,
    ) -> anyhow::Result<Host> {
        unsafe {
            let props = instance.get_physical_device_memory_properties(pd);
            let alloc = |req: vk::MemoryRequirements, want: vk::MemoryPropertyFlags| {
                let index = (0..props.memory_type_count)
                    .find(|&i| {
                        req.memory_type_bits & (1 << i) != 0
                            && props.memory_types[i as usize].property_flags.contains(want)
                    })
                    .expect("a memory type");
                device.allocate_memory(
                    &vk::MemoryAllocateInfo::default()
                        .allocation_size(req.size)
                        .memory_type_index(index),
                    None,
                )
            };
            let image = device.create_image(
                &vk::ImageCreateInfo::default()
                    .image_type(vk::ImageType::TYPE_2D)
                    .format(vk::Format::R32G32B32A32_SFLOAT)
                    .extent(vk::Extent3D {
                        width: W,
                        height: H,
                        depth: 1,
                    })
                    .mip_levels(1)
                    .array_layers(1)
                    .samples(vk::SampleCountFlags::TYPE_1)
                    .usage(vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC),
                None,
            )?;
            let image_memory = alloc(
                device.get_image_memory_requirements(image),
                vk::MemoryPropertyFlags::DEVICE_LOCAL,
            )?;
            device.bind_image_memory(image, image_memory, 0)?;
            let view = device.create_image_view(
                &vk::ImageViewCreateInfo::default()
                    .image(image)
                    .view_type(vk::ImageViewType::TYPE_2D)
                    .format(vk::Format::R32G32B32A32_SFLOAT)
                    .subresource_range(COLOR),
                None,
            )?;
            let buffer = device.create_buffer(
                &vk::BufferCreateInfo::default()
                    .size(u64::from(W * H) * 16)
                    .usage(vk::BufferUsageFlags::TRANSFER_DST),
                None,
            )?;
            let buffer_memory = alloc(
                device.get_buffer_memory_requirements(buffer),
                vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT,
            )?;
            device.bind_buffer_memory(buffer, buffer_memory, 0)?;
            let pool = device.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(qf)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )?;
            let cmd = device.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(pool)
                    .command_buffer_count(1),
            )?[0];
            Ok(Host {
                device: device.clone(),
                image,
                view,
                buffer,
                memory: [image_memory, buffer_memory],
                pool,
                cmd,
                fence: device.create_fence(&vk::FenceCreateInfo::default(), None)?,
                queue: device.get_device_queue(qf, 0),
            })
        }
    }

    /// The image as this application uses it: contents discarded before a pass, copied after.
    fn target(&self) -> TargetImage {
        TargetImage {
            image: self.image,
            view: self.view,
            extent: [W, H],
            before: ImageState {
                layout: vk::ImageLayout::UNDEFINED,
                stage: vk::PipelineStageFlags::TRANSFER,
                access: vk::AccessFlags::empty(),
            },
            after: ImageState {
                layout: vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                stage: vk::PipelineStageFlags::TRANSFER,
                access: vk::AccessFlags::TRANSFER_READ,
            },
        }
    }

    /// One frame: illum's pass, then the application's copy of the image, submitted and waited.
    unsafe fn frame(
        &self,
        illum: impl FnOnce(vk::CommandBuffer) -> illum::Result<()>,
    ) -> anyhow::Result<()> {
        let d = &self.device;
        unsafe {
            d.reset_command_buffer(self.cmd, vk::CommandBufferResetFlags::empty())?;
            d.begin_command_buffer(self.cmd, &vk::CommandBufferBeginInfo::default())?;
            illum(self.cmd)?;
            d.cmd_copy_image_to_buffer(
                self.cmd,
                self.image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                self.buffer,
                &[vk::BufferImageCopy::default()
                    .image_subresource(vk::ImageSubresourceLayers {
                        aspect_mask: vk::ImageAspectFlags::COLOR,
                        mip_level: 0,
                        base_array_layer: 0,
                        layer_count: 1,
                    })
                    .image_extent(vk::Extent3D {
                        width: W,
                        height: H,
                        depth: 1,
                    })],
            );
            let to_host = [vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(vk::AccessFlags::HOST_READ)];
            d.cmd_pipeline_barrier(
                self.cmd,
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::HOST,
                vk::DependencyFlags::empty(),
                &to_host,
                &[],
                &[],
            );
            d.end_command_buffer(self.cmd)?;
            let cmds = [self.cmd];
            d.queue_submit(
                self.queue,
                &[vk::SubmitInfo::default().command_buffers(&cmds)],
                self.fence,
            )?;
            d.wait_for_fences(&[self.fence], true, u64::MAX)?;
            d.reset_fences(&[self.fence])?;
        }
        Ok(())
    }

    /// The last frame's image, RGBA per pixel.
    unsafe fn read(&self) -> Vec<[f32; 4]> {
        let n = (W * H) as usize;
        unsafe {
            let p = self
                .device
                .map_memory(
                    self.memory[1],
                    0,
                    (n * 16) as u64,
                    vk::MemoryMapFlags::empty(),
                )
                .expect("mapping the read-back buffer");
            let out = std::slice::from_raw_parts(p as *const [f32; 4], n).to_vec();
            self.device.unmap_memory(self.memory[1]);
            out
        }
    }

    unsafe fn destroy(self) {
        let d = &self.device;
        unsafe {
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.pool, None);
            d.destroy_buffer(self.buffer, None);
            d.destroy_image_view(self.view, None);
            d.destroy_image(self.image, None);
            for m in self.memory {
                d.free_memory(m, None);
            }
        }
    }
}

const COLOR: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};
