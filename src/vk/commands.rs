//! Recording and submitting one-off command buffers on umbra's own queue.

use super::breadcrumb::{self, CrumbBuffer, Trail};
use super::context::Abandoned;
use super::{Context, Recorder};
use crate::error::{Error, Result, VkContext};
use ash::vk;
use std::sync::atomic::Ordering;
use std::time::Duration;

/// How long a submission may run, by default, before umbra reports it instead of waiting forever.
pub(crate) const DEFAULT_SUBMIT_TIMEOUT: Duration = Duration::from_secs(600);

impl Context {
    /// Sets how long [`Context::submit`] waits for the GPU before it gives up with
    /// [`Error::Timeout`] naming the pass the GPU was running (default 600 s): a watchdog for
    /// hosts with a frame budget and for tests. Applies to every clone of this context.
    ///
    /// A submission that timed out may still be running: its command pool, fence and breadcrumb
    /// are kept until it finishes. Before dropping resources its work uses, make it finish and
    /// call [`Context::wait_idle`].
    pub fn set_submit_timeout(&self, timeout: Duration) {
        let ns = u64::try_from(timeout.as_nanos()).unwrap_or(u64::MAX);
        self.shared.submit_timeout_ns.store(ns, Ordering::Relaxed);
    }

    /// The timeout of [`Context::submit`] (see [`Context::set_submit_timeout`]).
    pub fn submit_timeout(&self) -> Duration {
        Duration::from_nanos(self.shared.submit_timeout_ns.load(Ordering::Relaxed))
    }

    /// Waits, up to the submit timeout, until every submission [`Context::submit`] gave up on
    /// has finished on the GPU, and frees what they held. Returns at once when there is none.
    pub fn wait_idle(&self) -> Result<()> {
        let timeout_ns = self.shared.submit_timeout_ns.load(Ordering::Relaxed);
        match self.shared.reclaim(Some(timeout_ns))? {
            (0, _) => Ok(()),
            (_, pass) => Err(Error::Timeout { seconds: timeout_ns as f64 * 1e-9, pass }),
        }
    }

    /// [`Context::submit`] through a [`Recorder`]: the barriers between what `record` records
    /// are derived from what each operation reads and writes, and one ends the command buffer.
    pub fn record<T>(&self, record: impl FnOnce(&mut Recorder<'_>) -> Result<T>) -> Result<T> {
        self.submit(|cmd| Recorder::run(self, cmd, record))
    }

    /// Records `record` into a fresh primary command buffer, submits it and waits for it.
    ///
    /// Each call has its own command pool, so threads may call this concurrently; the queue
    /// itself is locked only for the submission.
    ///
    /// The command buffer carries a GPU-written breadcrumb: after each kernel dispatched into
    /// it (through [`super::ComputePipeline::dispatch`]; the first 256), the GPU marks that
    /// dispatch finished in a small host-visible buffer. When waiting fails (a lost device, or
    /// no completion within [`Context::submit_timeout`]), the error names the first dispatch
    /// the GPU had not finished: the pass that was running. When the work never reached the GPU
    /// (a failed `vkQueueSubmit2`), it names the last pass recorded.
    pub fn submit<T>(&self, record: impl FnOnce(vk::CommandBuffer) -> Result<T>) -> Result<T> {
        let shared = &self.shared;
        let device = &shared.device;
        // Free what earlier timed-out submissions held, where the GPU has finished them.
        let _ = shared.reclaim(None);
        let crumb = shared.crumbs.lock().unwrap_or_else(|p| p.into_inner()).pop();
        let crumb = match crumb {
            Some(c) => Some(c),
            None => CrumbBuffer::new(shared)
                .inspect_err(|e| log::warn!("umbra: no pass breadcrumb for this submission: {e}"))
                .ok(),
        };
        if let Some(c) = &crumb {
            c.zero();
        }
        let timeout_ns = shared.submit_timeout_ns.load(Ordering::Relaxed);
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(shared.queue_family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: valid device; the pool, fence and command buffer are destroyed below, or kept
        // in `abandoned` until the GPU has finished with them.
        unsafe {
            let idle = shared.idle_pools.lock().unwrap_or_else(|p| p.into_inner()).pop();
            let (pool, idle_cmd) = match idle {
                Some((pool, cmd)) => (pool, Some(cmd)),
                None => match device.create_command_pool(&pool_info, None).call("vkCreateCommandPool") {
                    Ok(pool) => (pool, None),
                    Err(e) => {
                        shared.crumbs.lock().unwrap_or_else(|p| p.into_inner()).extend(crumb);
                        return Err(e);
                    }
                },
            };
            let mut fence = vk::Fence::null();
            let mut submitted = false;
            let mut timed_out = false;
            let mut recorded = None;
            let result = (|| {
                let cmd = match idle_cmd {
                    Some(cmd) => cmd,
                    None => device
                        .allocate_command_buffers(
                            &vk::CommandBufferAllocateInfo::default()
                                .command_pool(pool)
                                .level(vk::CommandBufferLevel::PRIMARY)
                                .command_buffer_count(1),
                        )
                        .call("vkAllocateCommandBuffers")?[0],
                };
                recorded = Some(cmd);
                if let Some(c) = &crumb {
                    let trail = Trail { buffer: c.raw, passes: Vec::new() };
                    shared.trails.lock().unwrap_or_else(|p| p.into_inner()).insert(cmd, trail);
                }
                device
                    .begin_command_buffer(
                        cmd,
                        &vk::CommandBufferBeginInfo::default()
                            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                    )
                    .call("vkBeginCommandBuffer")?;
                let value = record(cmd)?;
                device.end_command_buffer(cmd).call("vkEndCommandBuffer")?;
                fence = device.create_fence(&vk::FenceCreateInfo::default(), None).call("vkCreateFence")?;
                let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
                let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
                // Fault injection (the `testing` feature): fail as `vkQueueSubmit2` would, submitting
                // nothing. An engine's build has no such branch.
                #[cfg(feature = "testing")]
                if let Some(fault) = shared.injected_fault.lock().unwrap_or_else(|p| p.into_inner()).take() {
                    Err::<(), _>(fault).call("vkQueueSubmit2")?;
                }
                {
                    let queue = shared.queue.lock().unwrap_or_else(|p| p.into_inner());
                    device.queue_submit2(*queue, &submit, fence).call("vkQueueSubmit2")?;
                }
                submitted = true;
                // Fault injection (the `testing` feature): the work runs, then the wait reports
                // the fault, as a device lost while (or after) the GPU ran it would.
                #[cfg(feature = "testing")]
                let wait_fault = shared.injected_wait_fault.lock().unwrap_or_else(|p| p.into_inner()).take();
                #[cfg(not(feature = "testing"))]
                let wait_fault: Option<vk::Result> = None;
                let waited = device.wait_for_fences(&[fence], true, timeout_ns);
                timed_out = waited == Err(vk::Result::TIMEOUT);
                match (waited, wait_fault) {
                    (_, Some(fault)) => Err(fault).call("vkWaitForFences"),
                    (Err(vk::Result::TIMEOUT), None) => {
                        Err(Error::Timeout { seconds: timeout_ns as f64 * 1e-9, pass: None })
                    }
                    (other, None) => other.call("vkWaitForFences").map(|()| value),
                }
            })();
            let trail =
                recorded.and_then(|cmd| shared.trails.lock().unwrap_or_else(|p| p.into_inner()).remove(&cmd));
            let last = recorded.and_then(|cmd| self.last_pass(cmd));
            if let Some(cmd) = recorded {
                self.clear_pass(cmd);
            }
            // Name the pass: where the GPU got to when it ran the work, else the last recorded.
            let name_pass = || match (submitted, &trail, &crumb) {
                (true, Some(trail), Some(crumb)) => breadcrumb::describe(&trail.passes, &crumb.slots()),
                (false, _, _) => last.map(breadcrumb::never_submitted),
                _ => last.map(|p| format!("{p}, the last pass recorded")),
            };
            let result = result.map_err(|e| match e {
                Error::Vulkan { call, result, pass: None } => {
                    Error::Vulkan { call, result, pass: name_pass() }
                }
                Error::Timeout { seconds, pass: None } => Error::Timeout { seconds, pass: name_pass() },
                other => other,
            });
            if timed_out {
                // Still running: keep the fence, pool and breadcrumb until the GPU is done.
                shared.abandoned.lock().unwrap_or_else(|p| p.into_inner()).push(Abandoned {
                    fence,
                    pool,
                    crumb,
                    passes: trail.map(|t| t.passes).unwrap_or_default(),
                });
            } else {
                // Finished, failed, or never submitted: nothing of it is in use.
                device.destroy_fence(fence, None);
                // A pool whose work finished is reset and kept for the next submission (its
                // command buffer back in the initial state); after a failure it is destroyed.
                let reusable = match (&result, recorded) {
                    (Ok(_), Some(cmd)) => device
                        .reset_command_pool(pool, vk::CommandPoolResetFlags::empty())
                        .is_ok()
                        .then_some(cmd),
                    _ => None,
                };
                match reusable {
                    Some(cmd) => {
                        shared.idle_pools.lock().unwrap_or_else(|p| p.into_inner()).push((pool, cmd))
                    }
                    None => device.destroy_command_pool(pool, None),
                }
                shared.crumbs.lock().unwrap_or_else(|p| p.into_inner()).extend(crumb);
            }
            result
        }
    }
}
