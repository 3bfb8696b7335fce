//! The window's swapchain: each frame is composed on the host (RGBA8), copied into the acquired
//! swapchain image and presented. One frame in flight; a frame can also be read back from the
//! swapchain image it was presented from (the screenshot), so tests see what the window got.

use crate::vk::{Buffer, Context, ImageState, MemoryLocation, image_barrier};
use anyhow::{Context as _, Result, anyhow, bail};
use ash::vk;
use winit::raw_window_handle::{
    HasDisplayHandle, HasWindowHandle, RawDisplayHandle, RawWindowHandle,
};

/// The instance extensions a surface of `window` needs, or why it cannot have one.
pub fn instance_extensions(window: &winit::window::Window) -> Result<Vec<std::ffi::CString>> {
    let platform = match window.window_handle()?.as_raw() {
        RawWindowHandle::Xlib(_) => ash::khr::xlib_surface::NAME,
        RawWindowHandle::Xcb(_) => ash::khr::xcb_surface::NAME,
        other => bail!("illum view presents to X11 windows only, this one is {other:?}"),
    };
    Ok(vec![
        ash::khr::surface::NAME.to_owned(),
        platform.to_owned(),
    ])
}

pub struct Present {
    ctx: Context,
    surface_fn: ash::khr::surface::Instance,
    swapchain_fn: ash::khr::swapchain::Device,
    surface: vk::SurfaceKHR,
    swapchain: vk::SwapchainKHR,
    images: Vec<vk::Image>,
    /// Signalled by each image's copy, waited on by its presentation: one per image, as a
    /// semaphore may still be held by the presentation engine until its image comes back.
    rendered: Vec<vk::Semaphore>,
    acquired: vk::Semaphore,
    fence: vk::Fence,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    pub format: vk::Format,
    pub extent: [u32; 2],
    staging: Buffer,
    readback: Option<Buffer>,
    /// The swapchain no longer matches the window: recreate before the next frame.
    stale: bool,
}

impl Present {
    /// A surface of `window` and a swapchain of its size on illum's own device and queue.
    pub fn new(ctx: &Context, window: &winit::window::Window) -> Result<Present> {
        let surface = create_surface(ctx, window)?;
        let surface_fn = ash::khr::surface::Instance::new(&ctx.entry, &ctx.instance);
        // SAFETY: valid handles; the surface belongs to this instance.
        let supported = unsafe {
            surface_fn.get_physical_device_surface_support(
                ctx.physical_device,
                ctx.queue_family,
                surface,
            )
        };
        if !supported.unwrap_or(false) {
            // SAFETY: the surface is ours and unused.
            unsafe { surface_fn.destroy_surface(surface, None) };
            bail!(
                "{}: its compute queue family {} cannot present to this window",
                ctx.info().name,
                ctx.queue_family
            );
        }
        let swapchain_fn = ash::khr::swapchain::Device::new(&ctx.instance, &ctx.device);
        // SAFETY: plain object creation on illum's device.
        let (acquired, fence, pool) = unsafe {
            (
                ctx.device
                    .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)?,
                ctx.device.create_fence(
                    &vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED),
                    None,
                )?,
                ctx.device.create_command_pool(
                    &vk::CommandPoolCreateInfo::default()
                        .queue_family_index(ctx.queue_family)
                        .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                    None,
                )?,
            )
        };
        // SAFETY: the pool was just created.
        let cmd = unsafe {
            ctx.device.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(pool)
                    .level(vk::CommandBufferLevel::PRIMARY)
                    .command_buffer_count(1),
            )?[0]
        };
        let staging = ctx.create_buffer(
            "view frame",
            4,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        let size = window.inner_size();
        let mut p = Present {
            ctx: ctx.clone(),
            surface_fn,
            swapchain_fn,
            surface,
            swapchain: vk::SwapchainKHR::null(),
            images: Vec::new(),
            rendered: Vec::new(),
            acquired,
            fence,
            pool,
            cmd,
            format: vk::Format::UNDEFINED,
            extent: [size.width, size.height],
            staging,
            readback: None,
            stale: false,
        };
        p.recreate([size.width, size.height])?;
        Ok(p)
    }

    /// Whether the frame's bytes are B, G, R, A (else R, G, B, A).
    pub fn bgra(&self) -> bool {
        matches!(
            self.format,
            vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB
        )
    }

    /// The swapchain no longer matches the window (resized).
    pub fn invalidate(&mut self) {
        self.stale = true;
    }

    /// A swapchain for a window of `size` pixels (the surface's own extent where it has one).
    fn recreate(&mut self, size: [u32; 2]) -> Result<()> {
        let (ctx, pd) = (self.ctx.clone(), self.ctx.physical_device);
        // SAFETY: valid handles; the device is idle before the old swapchain goes.
        unsafe {
            ctx.device.device_wait_idle()?;
            let caps = self
                .surface_fn
                .get_physical_device_surface_capabilities(pd, self.surface)?;
            let formats = self
                .surface_fn
                .get_physical_device_surface_formats(pd, self.surface)?;
            let modes = self
                .surface_fn
                .get_physical_device_surface_present_modes(pd, self.surface)?;
            // The frame holds sRGB-encoded bytes: a copy does not convert, so an 8-bit UNORM or
            // SRGB format of either channel order shows them as they are.
            let format = [
                vk::Format::B8G8R8A8_UNORM,
                vk::Format::R8G8B8A8_UNORM,
                vk::Format::B8G8R8A8_SRGB,
                vk::Format::R8G8B8A8_SRGB,
            ]
            .into_iter()
            .find_map(|f| formats.iter().find(|s| s.format == f).copied())
            .ok_or_else(|| {
                anyhow!("the window's surface offers no 8-bit RGBA format: {formats:?}")
            })?;
            let usage = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC;
            if !caps.supported_usage_flags.contains(usage) {
                bail!(
                    "the window's swapchain images cannot be copied to and from ({:?})",
                    caps.supported_usage_flags
                );
            }
            let extent = if caps.current_extent.width != u32::MAX {
                caps.current_extent
            } else {
                vk::Extent2D {
                    width: size[0].clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                    height: size[1]
                        .clamp(caps.min_image_extent.height, caps.max_image_extent.height),
                }
            };
            if extent.width == 0 || extent.height == 0 {
                // Minimised: keep the old swapchain until the window has pixels again.
                self.stale = true;
                return Ok(());
            }
            let count = match caps.max_image_count {
                0 => caps.min_image_count + 1,
                most => (caps.min_image_count + 1).min(most),
            };
            // No tearing, no waiting for a vertical blank where the surface allows it.
            let mode = if modes.contains(&vk::PresentModeKHR::MAILBOX) {
                vk::PresentModeKHR::MAILBOX
            } else {
                vk::PresentModeKHR::FIFO
            };
            let alpha = if caps
                .supported_composite_alpha
                .contains(vk::CompositeAlphaFlagsKHR::OPAQUE)
            {
                vk::CompositeAlphaFlagsKHR::OPAQUE
            } else {
                vk::CompositeAlphaFlagsKHR::from_raw(
                    1 << caps.supported_composite_alpha.as_raw().trailing_zeros(),
                )
            };
            let old = self.swapchain;
            let swapchain = self.swapchain_fn.create_swapchain(
                &vk::SwapchainCreateInfoKHR::default()
                    .surface(self.surface)
                    .min_image_count(count)
                    .image_format(format.format)
                    .image_color_space(format.color_space)
                    .image_extent(extent)
                    .image_array_layers(1)
                    .image_usage(usage)
                    .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
                    .pre_transform(caps.current_transform)
                    .composite_alpha(alpha)
                    .present_mode(mode)
                    .clipped(true)
                    .old_swapchain(old),
                None,
            )?;
            self.destroy_swapchain();
            self.swapchain = swapchain;
            self.images = self.swapchain_fn.get_swapchain_images(swapchain)?;
            for _ in &self.images {
                self.rendered.push(
                    ctx.device
                        .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)?,
                );
            }
            self.format = format.format;
            self.extent = [extent.width, extent.height];
        }
        let bytes = 4 * u64::from(self.extent[0]) * u64::from(self.extent[1]);
        if self.staging.size != bytes {
            self.staging = self.ctx.create_buffer(
                "view frame",
                bytes,
                vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::CpuToGpu,
            )?;
            self.readback = None;
        }
        self.stale = false;
        Ok(())
    }

    fn destroy_swapchain(&mut self) {
        // SAFETY: the device is idle (recreate and drop wait for it).
        unsafe {
            for s in self.rendered.drain(..) {
                self.ctx.device.destroy_semaphore(s, None);
            }
            if self.swapchain != vk::SwapchainKHR::null() {
                self.swapchain_fn.destroy_swapchain(self.swapchain, None);
            }
        }
        self.swapchain = vk::SwapchainKHR::null();
    }

    /// Waits for the previous frame, then gives its bytes (RGBA8 or BGRA8 rows of the extent)
    /// to `compose` and presents them; returns false when the swapchain had to be rebuilt (the
    /// frame is skipped; the extent may have changed). With `capture`, the presented image is
    /// also read back: see [`Present::captured`].
    pub fn frame(
        &mut self,
        window: [u32; 2],
        capture: bool,
        compose: impl FnOnce(&mut [u8], [u32; 2]),
    ) -> Result<bool> {
        let dev = &self.ctx.device.clone();
        // SAFETY: one frame in flight: the fence says the last one's commands have completed,
        // so its command buffer, staging buffer and acquire semaphore are free again.
        unsafe {
            dev.wait_for_fences(&[self.fence], true, u64::MAX)?;
        }
        if self.stale || window != self.extent {
            self.recreate(window)?;
            if self.stale {
                return Ok(false);
            }
        }
        // SAFETY: valid swapchain and semaphore.
        let acquired = unsafe {
            self.swapchain_fn.acquire_next_image(
                self.swapchain,
                u64::MAX,
                self.acquired,
                vk::Fence::null(),
            )
        };
        let index = match acquired {
            Ok((i, _suboptimal)) => i,
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.stale = true;
                return Ok(false);
            }
            Err(e) => return Err(e).context("vkAcquireNextImageKHR"),
        };
        let extent = self.extent;
        let bytes = self
            .staging
            .mapped()
            .ok_or_else(|| anyhow!("the view's frame buffer is not host-visible"))?;
        compose(bytes, extent);
        let bytes = 4 * u64::from(extent[0]) * u64::from(extent[1]);
        if capture && self.readback.as_ref().is_none_or(|b| b.size != bytes) {
            self.readback = Some(self.ctx.create_buffer(
                "view screenshot",
                bytes,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?);
        }
        let image = self.images[index as usize];
        let region = vk::BufferImageCopy::default()
            .image_subresource(
                vk::ImageSubresourceLayers::default()
                    .aspect_mask(vk::ImageAspectFlags::COLOR)
                    .layer_count(1),
            )
            .image_extent(vk::Extent3D {
                width: extent[0],
                height: extent[1],
                depth: 1,
            });
        // SAFETY: the command buffer is free (fence above); every handle is live.
        unsafe {
            dev.reset_fences(&[self.fence])?;
            dev.begin_command_buffer(
                self.cmd,
                &vk::CommandBufferBeginInfo::default()
                    .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )?;
            let (undefined, dst, src, present) = (
                state(vk::ImageLayout::UNDEFINED, vk::AccessFlags::empty()),
                state(
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    vk::AccessFlags::TRANSFER_WRITE,
                ),
                state(
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    vk::AccessFlags::TRANSFER_READ,
                ),
                ImageState {
                    layout: vk::ImageLayout::PRESENT_SRC_KHR,
                    stage: vk::PipelineStageFlags::empty(),
                    access: vk::AccessFlags::empty(),
                },
            );
            image_barrier(dev, self.cmd, image, &undefined, &dst);
            dev.cmd_copy_buffer_to_image(
                self.cmd,
                self.staging.buffer,
                image,
                dst.layout,
                &[region],
            );
            let mut last = dst;
            if let (true, Some(rb)) = (capture, &self.readback) {
                image_barrier(dev, self.cmd, image, &dst, &src);
                dev.cmd_copy_image_to_buffer(self.cmd, image, src.layout, rb.buffer, &[region]);
                last = src;
            }
            image_barrier(dev, self.cmd, image, &last, &present);
            dev.end_command_buffer(self.cmd)?;
            let (waits, stages, signals, cmds) = (
                [self.acquired],
                [vk::PipelineStageFlags::TRANSFER],
                [self.rendered[index as usize]],
                [self.cmd],
            );
            dev.queue_submit(
                self.ctx.queue,
                &[vk::SubmitInfo::default()
                    .wait_semaphores(&waits)
                    .wait_dst_stage_mask(&stages)
                    .command_buffers(&cmds)
                    .signal_semaphores(&signals)],
                self.fence,
            )?;
            let (swapchains, indices) = ([self.swapchain], [index]);
            match self.swapchain_fn.queue_present(
                self.ctx.queue,
                &vk::PresentInfoKHR::default()
                    .wait_semaphores(&signals)
                    .swapchains(&swapchains)
                    .image_indices(&indices),
            ) {
                Ok(false) => {}
                Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => self.stale = true,
                Err(e) => return Err(e).context("vkQueuePresentKHR"),
            }
        }
        Ok(true)
    }

    /// The last frame read back (`capture`), as RGB8 rows of `extent`.
    pub fn captured(&mut self) -> Result<Option<(Vec<u8>, [u32; 2])>> {
        // SAFETY: waits for the frame that wrote the readback buffer.
        unsafe {
            self.ctx
                .device
                .wait_for_fences(&[self.fence], true, u64::MAX)?
        };
        let (bgra, extent) = (self.bgra(), self.extent);
        let Some(rb) = self.readback.as_mut() else {
            return Ok(None);
        };
        let px = rb
            .mapped()
            .ok_or_else(|| anyhow!("the screenshot buffer is not host-visible"))?;
        let rgb = px
            .chunks_exact(4)
            .flat_map(|p| {
                if bgra {
                    [p[2], p[1], p[0]]
                } else {
                    [p[0], p[1], p[2]]
                }
            })
            .collect();
        Ok(Some((rgb, extent)))
    }
}

/// An image in `layout` for the frame's copies (transfer stage).
fn state(layout: vk::ImageLayout, access: vk::AccessFlags) -> ImageState {
    ImageState {
        layout,
        stage: vk::PipelineStageFlags::TRANSFER,
        access,
    }
}

fn create_surface(ctx: &Context, window: &winit::window::Window) -> Result<vk::SurfaceKHR> {
    let display = window.display_handle()?.as_raw();
    let handle = window.window_handle()?.as_raw();
    // SAFETY: the handles are the live window's; the surface is destroyed before the instance
    // (Present holds a clone of the context, dropped after it).
    unsafe {
        match (display, handle) {
            (RawDisplayHandle::Xlib(d), RawWindowHandle::Xlib(w)) => {
                let dpy = d
                    .display
                    .ok_or_else(|| anyhow!("the X11 window has no display"))?;
                Ok(
                    ash::khr::xlib_surface::Instance::new(&ctx.entry, &ctx.instance)
                        .create_xlib_surface(
                            &vk::XlibSurfaceCreateInfoKHR::default()
                                .dpy(dpy.as_ptr() as *mut vk::Display)
                                .window(w.window),
                            None,
                        )?,
                )
            }
            (RawDisplayHandle::Xcb(d), RawWindowHandle::Xcb(w)) => {
                let conn = d
                    .connection
                    .ok_or_else(|| anyhow!("the X11 window has no XCB connection"))?;
                Ok(
                    ash::khr::xcb_surface::Instance::new(&ctx.entry, &ctx.instance)
                        .create_xcb_surface(
                            &vk::XcbSurfaceCreateInfoKHR::default()
                                .connection(conn.as_ptr())
                                .window(w.window.get()),
                            None,
                        )?,
                )
            }
            other => bail!("illum view presents to X11 windows only, not {other:?}"),
        }
    }
}

impl Drop for Present {
    fn drop(&mut self) {
        // SAFETY: the device is idle before anything of the frame is destroyed.
        unsafe {
            let _ = self.ctx.device.device_wait_idle();
            self.destroy_swapchain();
            self.ctx.device.destroy_semaphore(self.acquired, None);
            self.ctx.device.destroy_fence(self.fence, None);
            self.ctx.device.destroy_command_pool(self.pool, None);
            self.surface_fn.destroy_surface(self.surface, None);
        }
    }
}
