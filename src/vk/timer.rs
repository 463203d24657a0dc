//! GPU timestamp queries, reported in milliseconds per pass.

use super::{context::Shared, Context};
use crate::error::{Error, Result, VkContext};
use ash::vk;
use std::sync::Arc;

/// A named pass's GPU duration.
#[derive(Debug, Clone, PartialEq)]
pub struct PassTime {
    /// The pass.
    pub name: String,
    /// Its duration in milliseconds.
    pub ms: f64,
}

/// Timestamps around passes: `reset`, then `begin`/`end` pairs, then `read` after the
/// submission has finished.
pub struct GpuTimer {
    shared: Arc<Shared>,
    pool: vk::QueryPool,
    capacity: u32,
    names: Vec<String>,
    open: bool,
}

impl GpuTimer {
    /// A timer for up to `passes` passes per submission.
    pub fn new(ctx: &Context, passes: u32) -> Result<Self> {
        if ctx.info().timestamp_valid_bits == 0 {
            return Err(Error::Unsupported {
                device: ctx.info().name.clone(),
                missing: "timestamps on the compute queue".into(),
            });
        }
        let info =
            vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(2 * passes);
        // SAFETY: valid device; destroyed in Drop.
        let pool = unsafe { ctx.device().create_query_pool(&info, None) }.call("vkCreateQueryPool")?;
        Ok(Self { shared: ctx.shared.clone(), pool, capacity: passes, names: Vec::new(), open: false })
    }

    /// Resets every query; record before the first `begin` of a submission.
    pub fn reset(&mut self, cmd: vk::CommandBuffer) {
        self.names.clear();
        self.open = false;
        // SAFETY: recording state; the range is within the pool.
        unsafe { self.shared.device.cmd_reset_query_pool(cmd, self.pool, 0, 2 * self.capacity) };
    }

    /// Records `record` as pass `name` on `timer` when given (untimed without one): the steps of
    /// a pass that times its own kernels.
    pub fn time<T>(
        timer: &mut Option<&mut GpuTimer>,
        cmd: vk::CommandBuffer,
        name: &str,
        record: impl FnOnce() -> Result<T>,
    ) -> Result<T> {
        if let Some(t) = timer.as_deref_mut() {
            t.begin(cmd, name)?;
        }
        let recorded = record()?;
        if let Some(t) = timer.as_deref_mut() {
            t.end(cmd)?;
        }
        Ok(recorded)
    }

    /// Marks the start of pass `name`.
    pub fn begin(&mut self, cmd: vk::CommandBuffer, name: &str) -> Result<()> {
        if self.open || self.names.len() as u32 >= self.capacity {
            return Err(Error::Invalid(format!(
                "timer: cannot begin '{name}' ({} of {} passes used, one open: {})",
                self.names.len(),
                self.capacity,
                self.open
            )));
        }
        let query = 2 * self.names.len() as u32;
        self.names.push(name.to_string());
        self.open = true;
        // SAFETY: recording state; the query was reset.
        unsafe {
            self.shared.device.cmd_write_timestamp2(
                cmd,
                vk::PipelineStageFlags2::ALL_COMMANDS,
                self.pool,
                query,
            )
        };
        Ok(())
    }

    /// Marks the end of the open pass.
    pub fn end(&mut self, cmd: vk::CommandBuffer) -> Result<()> {
        if !self.open {
            return Err(Error::Invalid("timer: end without begin".into()));
        }
        self.open = false;
        let query = 2 * self.names.len() as u32 - 1;
        // SAFETY: recording state; the query was reset.
        unsafe {
            self.shared.device.cmd_write_timestamp2(
                cmd,
                vk::PipelineStageFlags2::ALL_COMMANDS,
                self.pool,
                query,
            )
        };
        Ok(())
    }

    /// Each pass's duration; call after the submission has completed.
    pub fn read(&self) -> Result<Vec<PassTime>> {
        let count = 2 * self.names.len();
        if count == 0 {
            return Ok(Vec::new());
        }
        let mut ticks = vec![0u64; count];
        // SAFETY: the queries were written by a finished submission.
        unsafe {
            self.shared.device.get_query_pool_results(
                self.pool,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .call("vkGetQueryPoolResults")?;
        let bits = self.shared.info.timestamp_valid_bits;
        let mask = if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 };
        let period = self.shared.info.timestamp_period as f64;
        Ok(self
            .names
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let delta = ticks[2 * i + 1].wrapping_sub(ticks[2 * i]) & mask;
                PassTime { name: name.clone(), ms: delta as f64 * period * 1e-6 }
            })
            .collect())
    }
}

impl Drop for GpuTimer {
    fn drop(&mut self) {
        // SAFETY: no pending submission uses the pool.
        unsafe { self.shared.device.destroy_query_pool(self.pool, None) };
    }
}
