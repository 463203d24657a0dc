//! Recording and submitting one-off command buffers on umbra's own queue.

use super::Context;
use crate::error::{Error, Result, VkContext};
use ash::vk;

/// How long a submission may run before umbra reports it instead of waiting forever.
const SUBMIT_TIMEOUT_NS: u64 = 600 * 1_000_000_000;

impl Context {
    /// Records `record` into a fresh primary command buffer, submits it and waits for it.
    ///
    /// Each call has its own command pool, so threads may call this concurrently; the queue
    /// itself is locked only for the submission.
    pub fn submit<T>(&self, record: impl FnOnce(vk::CommandBuffer) -> Result<T>) -> Result<T> {
        let device = &self.shared.device;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(self.shared.queue_family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: valid device; the pool, fence and command buffer are destroyed below.
        unsafe {
            let pool = device.create_command_pool(&pool_info, None).call("vkCreateCommandPool")?;
            let mut still_running = false;
            let mut recorded = None;
            let result = (|| {
                let cmd = device
                    .allocate_command_buffers(
                        &vk::CommandBufferAllocateInfo::default()
                            .command_pool(pool)
                            .level(vk::CommandBufferLevel::PRIMARY)
                            .command_buffer_count(1),
                    )
                    .call("vkAllocateCommandBuffers")?[0];
                recorded = Some(cmd);
                device
                    .begin_command_buffer(
                        cmd,
                        &vk::CommandBufferBeginInfo::default()
                            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                    )
                    .call("vkBeginCommandBuffer")?;
                let value = record(cmd)?;
                device.end_command_buffer(cmd).call("vkEndCommandBuffer")?;
                let fence =
                    device.create_fence(&vk::FenceCreateInfo::default(), None).call("vkCreateFence")?;
                let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
                let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
                let injected = self.shared.injected_fault.lock().unwrap_or_else(|p| p.into_inner()).take();
                let submitted = match injected {
                    Some(fault) => Err(fault).call("vkQueueSubmit2"),
                    None => {
                        let queue = self.shared.queue.lock().unwrap_or_else(|p| p.into_inner());
                        device.queue_submit2(*queue, &submit, fence).call("vkQueueSubmit2")
                    }
                };
                let waited = submitted.and_then(|()| {
                    match device.wait_for_fences(&[fence], true, SUBMIT_TIMEOUT_NS) {
                        Err(vk::Result::TIMEOUT) => Err(Error::Invalid(format!(
                            "GPU work did not finish within {} s",
                            SUBMIT_TIMEOUT_NS / 1_000_000_000
                        ))),
                        other => other.call("vkWaitForFences"),
                    }
                });
                if let Err(Error::Invalid(message)) = waited {
                    // Still running: leak the fence and pool rather than free them under the GPU.
                    still_running = true;
                    return Err(Error::Invalid(match self.last_pass(cmd) {
                        Some(pass) => format!("{message} (last pass recorded: {pass})"),
                        None => message,
                    }));
                }
                device.destroy_fence(fence, None);
                waited.map(|()| value)
            })();
            // The pass marker: a Vulkan error names the last pass recorded before it.
            let pass = recorded.and_then(|cmd| self.last_pass(cmd));
            let result = result.map_err(|e| match e {
                Error::Vulkan { call, result, pass: None } => {
                    Error::Vulkan { call, result, pass: pass.map(String::from) }
                }
                other => other,
            });
            if let Some(cmd) = recorded {
                self.clear_pass(cmd);
            }
            // A recording that failed never reached the queue: its pool goes too.
            if !still_running {
                device.destroy_command_pool(pool, None);
            }
            result
        }
    }
}
