//! The host application's side of a frame: its own storage image for illum, a render pass of its
//! own (a clear of its colour image), a copy of illum's image into a readback buffer, its own
//! command buffer and fence: everything an engine's frame loop has around `record_pass`. It may
//! have several storage images for illum (the beauty, then AOV planes), all copied back.

use ash::vk;
use illum::render::{ImageState, TargetImage};

pub struct HostFrame {
    device: ash::Device,
    /// illum's storage images and their views: the beauty's first.
    targets: Vec<(vk::Image, vk::ImageView)>,
    color: vk::Image,
    color_view: vk::ImageView,
    render_pass: vk::RenderPass,
    framebuffer: vk::Framebuffer,
    readback: vk::Buffer,
    memory: Vec<vk::DeviceMemory>,
    pool: vk::CommandPool,
    pub cmd: vk::CommandBuffer,
    fence: vk::Fence,
    queue: vk::Queue,
    pub extent: [u32; 2],
}

unsafe fn bind_memory(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    device: &ash::Device,
    req: vk::MemoryRequirements,
    flags: vk::MemoryPropertyFlags,
) -> vk::DeviceMemory {
    unsafe {
        let props = instance.get_physical_device_memory_properties(pd);
        let index = (0..props.memory_type_count)
            .find(|&i| {
                req.memory_type_bits & (1 << i) != 0
                    && props.memory_types[i as usize]
                        .property_flags
                        .contains(flags)
            })
            .expect("a memory type");
        device
            .allocate_memory(
                &vk::MemoryAllocateInfo::default()
                    .allocation_size(req.size)
                    .memory_type_index(index),
                None,
            )
            .unwrap()
    }
}

fn image_info(
    format: vk::Format,
    usage: vk::ImageUsageFlags,
    e: [u32; 2],
) -> vk::ImageCreateInfo<'static> {
    vk::ImageCreateInfo::default()
        .image_type(vk::ImageType::TYPE_2D)
        .format(format)
        .extent(vk::Extent3D {
            width: e[0],
            height: e[1],
            depth: 1,
        })
        .mip_levels(1)
        .array_layers(1)
        .samples(vk::SampleCountFlags::TYPE_1)
        .tiling(vk::ImageTiling::OPTIMAL)
        .usage(usage)
        .initial_layout(vk::ImageLayout::UNDEFINED)
}

const COLOR: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};

impl HostFrame {
    /// # Safety
    /// Valid handles; the frame is destroyed (`destroy`) before the device.
    pub unsafe fn new(
        instance: &ash::Instance,
        pd: vk::PhysicalDevice,
        device: &ash::Device,
        queue_family: u32,
        extent: [u32; 2],
    ) -> HostFrame {
        // SAFETY: the caller's contract.
        unsafe { Self::with_images(instance, pd, device, queue_family, extent, 1) }
    }

    /// A frame with `images` storage images for illum.
    ///
    /// # Safety
    /// As [`HostFrame::new`].
    pub unsafe fn with_images(
        instance: &ash::Instance,
        pd: vk::PhysicalDevice,
        device: &ash::Device,
        queue_family: u32,
        extent: [u32; 2],
        images: usize,
    ) -> HostFrame {
        unsafe {
            let mut memory = Vec::new();
            let mut image = |format, usage| {
                let i = device
                    .create_image(&image_info(format, usage, extent), None)
                    .unwrap();
                let m = bind_memory(
                    instance,
                    pd,
                    device,
                    device.get_image_memory_requirements(i),
                    vk::MemoryPropertyFlags::DEVICE_LOCAL,
                );
                device.bind_image_memory(i, m, 0).unwrap();
                memory.push(m);
                let v = device
                    .create_image_view(
                        &vk::ImageViewCreateInfo::default()
                            .image(i)
                            .view_type(vk::ImageViewType::TYPE_2D)
                            .format(format)
                            .subresource_range(COLOR),
                        None,
                    )
                    .unwrap();
                (i, v)
            };
            let targets: Vec<_> = (0..images)
                .map(|_| {
                    image(
                        vk::Format::R32G32B32A32_SFLOAT,
                        vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC,
                    )
                })
                .collect();
            let (color, color_view) = image(
                vk::Format::R8G8B8A8_UNORM,
                vk::ImageUsageFlags::COLOR_ATTACHMENT,
            );
            let readback = device
                .create_buffer(
                    &vk::BufferCreateInfo::default()
                        .size(u64::from(extent[0] * extent[1]) * 16 * images as u64)
                        .usage(vk::BufferUsageFlags::TRANSFER_DST),
                    None,
                )
                .unwrap();
            let m = bind_memory(
                instance,
                pd,
                device,
                device.get_buffer_memory_requirements(readback),
                vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT,
            );
            device.bind_buffer_memory(readback, m, 0).unwrap();
            memory.push(m);
            let attachment = [vk::AttachmentDescription::default()
                .format(vk::Format::R8G8B8A8_UNORM)
                .samples(vk::SampleCountFlags::TYPE_1)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::STORE)
                .initial_layout(vk::ImageLayout::UNDEFINED)
                .final_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)];
            let refs = [vk::AttachmentReference::default()
                .attachment(0)
                .layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)];
            let subpass = [vk::SubpassDescription::default()
                .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
                .color_attachments(&refs)];
            // The previous frame's store before this frame's clear.
            let dep = [vk::SubpassDependency::default()
                .src_subpass(vk::SUBPASS_EXTERNAL)
                .dst_subpass(0)
                .src_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
                .dst_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
                .src_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE)
                .dst_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE)];
            let render_pass = device
                .create_render_pass(
                    &vk::RenderPassCreateInfo::default()
                        .attachments(&attachment)
                        .subpasses(&subpass)
                        .dependencies(&dep),
                    None,
                )
                .unwrap();
            let views = [color_view];
            let framebuffer = device
                .create_framebuffer(
                    &vk::FramebufferCreateInfo::default()
                        .render_pass(render_pass)
                        .attachments(&views)
                        .width(extent[0])
                        .height(extent[1])
                        .layers(1),
                    None,
                )
                .unwrap();
            let pool = device
                .create_command_pool(
                    &vk::CommandPoolCreateInfo::default()
                        .queue_family_index(queue_family)
                        .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                    None,
                )
                .unwrap();
            let cmd = device
                .allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default()
                        .command_pool(pool)
                        .command_buffer_count(1),
                )
                .unwrap()[0];
            let fence = device
                .create_fence(&vk::FenceCreateInfo::default(), None)
                .unwrap();
            HostFrame {
                device: device.clone(),
                targets,
                color,
                color_view,
                render_pass,
                framebuffer,
                readback,
                memory,
                pool,
                cmd,
                fence,
                queue: device.get_device_queue(queue_family, 0),
                extent,
            }
        }
    }

    /// illum's (beauty) image as this host uses it: discarded before each pass, copied after.
    pub fn target(&self) -> TargetImage {
        self.target_at(0)
    }

    /// Storage image `k` for illum, used as [`HostFrame::target`].
    pub fn target_at(&self, k: usize) -> TargetImage {
        TargetImage {
            image: self.targets[k].0,
            view: self.targets[k].1,
            extent: self.extent,
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

    /// One frame: the host's render pass, then `illum` records into the same command buffer,
    /// then the host copies illum's image for readback; submitted and waited for. Returns the
    /// image's RGBA texels.
    pub fn frame(&self, illum: impl FnOnce(vk::CommandBuffer)) -> Vec<[f32; 4]> {
        self.frame_all(illum).swap_remove(0)
    }

    /// [`HostFrame::frame`], returning the texels of every storage image.
    pub fn frame_all(&self, illum: impl FnOnce(vk::CommandBuffer)) -> Vec<Vec<[f32; 4]>> {
        let d = &self.device;
        // SAFETY: every object is this frame's; the fence wait ends the frame.
        unsafe {
            d.reset_command_buffer(self.cmd, vk::CommandBufferResetFlags::empty())
                .unwrap();
            d.begin_command_buffer(self.cmd, &vk::CommandBufferBeginInfo::default())
                .unwrap();
            let clear = [vk::ClearValue {
                color: vk::ClearColorValue {
                    float32: [0.1, 0.2, 0.3, 1.0],
                },
            }];
            d.cmd_begin_render_pass(
                self.cmd,
                &vk::RenderPassBeginInfo::default()
                    .render_pass(self.render_pass)
                    .framebuffer(self.framebuffer)
                    .render_area(vk::Rect2D {
                        offset: vk::Offset2D::default(),
                        extent: vk::Extent2D {
                            width: self.extent[0],
                            height: self.extent[1],
                        },
                    })
                    .clear_values(&clear),
                vk::SubpassContents::INLINE,
            );
            d.cmd_end_render_pass(self.cmd);
            illum(self.cmd);
            let n = u64::from(self.extent[0] * self.extent[1]);
            for (k, t) in self.targets.iter().enumerate() {
                d.cmd_copy_image_to_buffer(
                    self.cmd,
                    t.0,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    self.readback,
                    &[vk::BufferImageCopy::default()
                        .buffer_offset(k as u64 * n * 16)
                        .image_subresource(vk::ImageSubresourceLayers {
                            aspect_mask: vk::ImageAspectFlags::COLOR,
                            mip_level: 0,
                            base_array_layer: 0,
                            layer_count: 1,
                        })
                        .image_extent(vk::Extent3D {
                            width: self.extent[0],
                            height: self.extent[1],
                            depth: 1,
                        })],
                );
            }
            // The copy's writes made visible to the host's read of the mapped buffer.
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
            d.end_command_buffer(self.cmd).unwrap();
            let cmds = [self.cmd];
            d.queue_submit(
                self.queue,
                &[vk::SubmitInfo::default().command_buffers(&cmds)],
                self.fence,
            )
            .unwrap();
            d.wait_for_fences(&[self.fence], true, u64::MAX).unwrap();
            d.reset_fences(&[self.fence]).unwrap();
            let n = (self.extent[0] * self.extent[1]) as usize;
            let k = self.targets.len();
            let mem = *self.memory.last().unwrap();
            let p = d
                .map_memory(mem, 0, (k * n * 16) as u64, vk::MemoryMapFlags::empty())
                .unwrap();
            let all = std::slice::from_raw_parts(p as *const [f32; 4], k * n);
            let out = all.chunks_exact(n).map(<[_]>::to_vec).collect();
            d.unmap_memory(mem);
            out
        }
    }

    pub fn destroy(self) {
        let d = &self.device;
        // SAFETY: the last frame was waited for.
        unsafe {
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.pool, None);
            d.destroy_framebuffer(self.framebuffer, None);
            d.destroy_render_pass(self.render_pass, None);
            d.destroy_buffer(self.readback, None);
            d.destroy_image_view(self.color_view, None);
            d.destroy_image(self.color, None);
            for (image, view) in &self.targets {
                d.destroy_image_view(*view, None);
                d.destroy_image(*image, None);
            }
            for m in &self.memory {
                d.free_memory(*m, None);
            }
        }
    }
}
