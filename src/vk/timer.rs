//! Device time of submissions, from timestamp queries written around the recorded work.

use super::context::Context;
use super::error::{Result, VkResultExt};
use ash::vk;

/// Two timestamps around one submission's work; None where the queue has no timestamps.
pub struct GpuTimer {
    ctx: Context,
    pool: vk::QueryPool,
}

impl GpuTimer {
    pub fn new(ctx: &Context) -> Result<Option<GpuTimer>> {
        if ctx.timestamp_bits == 0 {
            return Ok(None);
        }
        // SAFETY: valid device; the pool is destroyed in Drop.
        let pool = unsafe {
            ctx.device.create_query_pool(
                &vk::QueryPoolCreateInfo::default()
                    .query_type(vk::QueryType::TIMESTAMP)
                    .query_count(2),
                None,
            )
        }
        .vk("vkCreateQueryPool")?;
        Ok(Some(GpuTimer {
            ctx: ctx.clone(),
            pool,
        }))
    }

    /// Records the start timestamp (call first in the command buffer).
    pub fn start(&self, cmd: vk::CommandBuffer) {
        // SAFETY: cmd is recording; the pool is alive.
        unsafe {
            self.ctx.device.cmd_reset_query_pool(cmd, self.pool, 0, 2);
            self.ctx.device.cmd_write_timestamp(
                cmd,
                vk::PipelineStageFlags::TOP_OF_PIPE,
                self.pool,
                0,
            );
        }
    }

    /// Records the end timestamp (call last in the command buffer).
    pub fn stop(&self, cmd: vk::CommandBuffer) {
        // SAFETY: as in start.
        unsafe {
            self.ctx.device.cmd_write_timestamp(
                cmd,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                self.pool,
                1,
            )
        }
    }

    /// Records `record` into `cmd` between the two timestamps of `timer`, or alone without one.
    pub fn around<R>(
        timer: Option<&GpuTimer>,
        cmd: vk::CommandBuffer,
        record: impl FnOnce() -> R,
    ) -> R {
        if let Some(t) = timer {
            t.start(cmd);
        }
        let r = record();
        if let Some(t) = timer {
            t.stop(cmd);
        }
        r
    }

    /// Seconds between the two timestamps of the last completed submission.
    pub fn seconds(&self) -> Result<f64> {
        let mut t = [0u64; 2];
        // SAFETY: both queries were written by a submission that completed.
        unsafe {
            self.ctx.device.get_query_pool_results(
                self.pool,
                0,
                &mut t,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .vk("vkGetQueryPoolResults")?;
        let mask = if self.ctx.timestamp_bits >= 64 {
            u64::MAX
        } else {
            (1u64 << self.ctx.timestamp_bits) - 1
        };
        let ticks = t[1].wrapping_sub(t[0]) & mask;
        Ok(ticks as f64 * self.ctx.timestamp_period * 1e-9)
    }
}

impl Drop for GpuTimer {
    fn drop(&mut self) {
        // SAFETY: no pending work uses the pool.
        unsafe { self.ctx.device.destroy_query_pool(self.pool, None) };
    }
}
