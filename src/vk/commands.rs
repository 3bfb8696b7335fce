//! Command submission: record, submit, wait. Every submission is bounded by the caller (tiles and
//! sample batches) so that none runs long enough to trip a driver watchdog.

use super::context::Context;
use super::error::{Result, VkResultExt};
use ash::vk;

impl Context {
    /// Records one command buffer with `record`, submits it and waits for it to finish.
    pub fn one_shot<R>(&self, record: impl FnOnce(vk::CommandBuffer) -> R) -> Result<R> {
        let pool = self.command_pool.lock().unwrap_or_else(|p| p.into_inner());
        // SAFETY: the pool is locked for the whole recording and submission; the command buffer
        // and fence are freed before returning.
        unsafe {
            let cmd = self
                .device
                .allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default()
                        .command_pool(*pool)
                        .level(vk::CommandBufferLevel::PRIMARY)
                        .command_buffer_count(1),
                )
                .vk("vkAllocateCommandBuffers")?[0];
            let free = || self.device.free_command_buffers(*pool, &[cmd]);
            if let Err(e) = self
                .device
                .begin_command_buffer(
                    cmd,
                    &vk::CommandBufferBeginInfo::default()
                        .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                )
                .vk("vkBeginCommandBuffer")
            {
                free();
                return Err(e);
            }
            let out = record(cmd);
            let result = (|| {
                self.device
                    .end_command_buffer(cmd)
                    .vk("vkEndCommandBuffer")?;
                let fence = self
                    .device
                    .create_fence(&vk::FenceCreateInfo::default(), None)
                    .vk("vkCreateFence")?;
                let cmds = [cmd];
                let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
                let r = self
                    .device
                    .queue_submit(self.queue, &submit, fence)
                    .vk("vkQueueSubmit")
                    .and_then(|_| {
                        self.device
                            .wait_for_fences(&[fence], true, u64::MAX)
                            .vk("vkWaitForFences")
                    });
                self.device.destroy_fence(fence, None);
                r
            })();
            free();
            result.map(|_| out)
        }
    }

    /// A full memory barrier between compute/transfer/acceleration-structure work in `cmd`.
    pub fn barrier(&self, cmd: vk::CommandBuffer) {
        let mb = [vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::MEMORY_WRITE)
            .dst_access_mask(vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE)];
        // SAFETY: cmd is in the recording state (called from within one_shot).
        unsafe {
            self.device.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::DependencyFlags::empty(),
                &mb,
                &[],
                &[],
            )
        }
    }
}

/// Where an image is: its layout and the stages and accesses of the commands around.
#[derive(Clone, Copy, Debug)]
pub struct ImageState {
    pub layout: vk::ImageLayout,
    pub stage: vk::PipelineStageFlags,
    pub access: vk::AccessFlags,
}

/// Records a barrier moving `image` (one colour mip and layer) from state `from` to `to`
/// (an empty stage mask stands for the top, resp. bottom, of the pipe).
///
/// # Safety
/// `cmd` must be in the recording state, `image` a live image of `dev`.
pub unsafe fn image_barrier(
    dev: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    from: &ImageState,
    to: &ImageState,
) {
    let or_top = |s: vk::PipelineStageFlags, fallback| if s.is_empty() { fallback } else { s };
    let b = [vk::ImageMemoryBarrier::default()
        .old_layout(from.layout)
        .new_layout(to.layout)
        .src_access_mask(from.access)
        .dst_access_mask(to.access)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(
            vk::ImageSubresourceRange::default()
                .aspect_mask(vk::ImageAspectFlags::COLOR)
                .level_count(1)
                .layer_count(1),
        )];
    // SAFETY: the caller's contract.
    unsafe {
        dev.cmd_pipeline_barrier(
            cmd,
            or_top(from.stage, vk::PipelineStageFlags::TOP_OF_PIPE),
            or_top(to.stage, vk::PipelineStageFlags::BOTTOM_OF_PIPE),
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &b,
        )
    }
}
