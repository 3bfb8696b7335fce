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
