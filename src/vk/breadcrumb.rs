//! The GPU-written pass breadcrumb of umbra's own submissions ([`super::Context::submit`]).
//!
//! Each command buffer `submit` records gets a small host-visible buffer of [`SLOTS`] zeroed
//! `u32`s. After dispatch `i` (0-based) of that command buffer, an execution barrier (compute
//! shader → transfer) and `vkCmdFillBuffer(slot i, i + 1)` follow, so the GPU itself marks each
//! dispatch finished. When the submission fails (a Vulkan error while waiting, a lost device, or
//! the timeout), the first slot still 0 is the dispatch the GPU was running, or would have run
//! next, and the error names its pass.
//!
//! Synchronization: the barrier only orders the fill after the dispatch (an execution
//! dependency: the fill writes no memory a kernel touches, and no kernel reads the breadcrumb, so
//! neither side needs an access mask), and the fills write disjoint 4-byte ranges, so they need
//! no barrier between each other or toward later passes. The host reads the slots without
//! waiting for the fence: that is the point, and the memory is host-coherent; the reading is
//! best-effort diagnostics, never used for anything but the message.
//!
//! Cost on lavapipe: no difference above the noise in `umbra-bench passes` (ms-long passes);
//! about 0.3–1 µs per dispatch in a submission of 200 tiny dispatches (~13 µs each). On a real
//! GPU the barrier also ends the overlap of back-to-back dispatches that had no barrier between
//! them (umbra's passes already put one after each).
//!
//! A host's own command buffers (recording through [`crate::embed`]) get no breadcrumb: there
//! the host owns diagnostics and [`super::Context::last_pass`] names the last pass recorded.

use super::context::Shared;
use crate::error::{Error, Result};
use ash::vk;
use gpu_allocator::vulkan::Allocation;
use gpu_allocator::MemoryLocation;

/// Dispatches tracked per command buffer; later ones are counted but not written.
pub(crate) const SLOTS: usize = 256;

/// A host-visible, host-coherent buffer of [`SLOTS`] `u32`s (pooled in [`Shared`]).
pub(crate) struct CrumbBuffer {
    pub raw: vk::Buffer,
    allocation: Allocation,
}

impl CrumbBuffer {
    pub fn new(shared: &Shared) -> Result<Self> {
        let (raw, allocation) = super::buffer::create_bound(
            shared,
            "pass breadcrumb",
            (SLOTS * 4) as u64,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        let crumb = Self { raw, allocation };
        if let Err(e) = crumb.slots_ptr() {
            crumb.destroy(shared);
            return Err(e);
        }
        Ok(crumb)
    }

    fn slots_ptr(&self) -> Result<*mut u32> {
        self.allocation
            .mapped_ptr()
            .map(|p| p.as_ptr().cast::<u32>())
            .ok_or_else(|| Error::Invalid("the pass breadcrumb is not host-visible".into()))
    }

    /// Zeroes every slot (before the command buffer is submitted).
    pub fn zero(&self) {
        if let Ok(p) = self.slots_ptr() {
            // SAFETY: a mapping of at least SLOTS u32s that no GPU work uses now.
            unsafe { std::ptr::write_bytes(p, 0, SLOTS) };
        }
    }

    /// The slots as the GPU has written them so far (it may still be writing).
    pub fn slots(&self) -> Vec<u32> {
        match self.slots_ptr() {
            // SAFETY: a live mapping of SLOTS u32s; volatile, as the GPU may write concurrently.
            Ok(p) => (0..SLOTS).map(|i| unsafe { p.add(i).read_volatile() }).collect(),
            Err(_) => Vec::new(),
        }
    }

    /// Frees the buffer; no pending GPU work may use it.
    pub fn destroy(self, shared: &Shared) {
        // SAFETY: the caller guarantees the GPU is done with it.
        unsafe { shared.device.destroy_buffer(self.raw, None) };
        let _ = shared.allocator().free(self.allocation);
    }
}

/// The dispatches recorded so far into one of `submit`'s command buffers.
pub(crate) struct Trail {
    pub buffer: vk::Buffer,
    pub passes: Vec<&'static str>,
}

impl Trail {
    /// Records the marker for the dispatch just recorded into `cmd`: an execution barrier after
    /// it, then the fill of its slot. Past [`SLOTS`] the pass is only counted.
    pub fn after_dispatch(&mut self, device: &ash::Device, cmd: vk::CommandBuffer, pass: &'static str) {
        let i = self.passes.len();
        self.passes.push(pass);
        if i >= SLOTS {
            return;
        }
        let barrier = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
            .dst_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)];
        // SAFETY: `cmd` is recording; the buffer holds SLOTS u32s and outlives the submission.
        unsafe {
            device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&barrier));
            device.cmd_fill_buffer(cmd, self.buffer, 4 * i as u64, 4, i as u32 + 1);
        }
    }
}

/// Names the pass the GPU had reached: the first dispatch whose slot is not yet written.
/// `passes` are the kernels dispatched in recording order, `slots` the breadcrumb as read back.
pub(crate) fn describe(passes: &[&str], slots: &[u32]) -> Option<String> {
    let n = passes.len();
    let last = *passes.last()?;
    let tracked = n.min(SLOTS).min(slots.len());
    let finished = (0..tracked).take_while(|&i| slots[i] == i as u32 + 1).count();
    Some(if finished < tracked {
        format!(
            "{}, dispatch {} of {n}: running or next to run on the GPU; {finished} finished",
            passes[finished],
            finished + 1
        )
    } else if tracked == n {
        format!("{last}, the last of {n} dispatches: all finished on the GPU")
    } else {
        format!(
            "{last}, dispatch {n} of {n}, the last recorded: the first {tracked} finished on the GPU; \
             the breadcrumb tracks no more"
        )
    })
}

/// The message when the work never reached the GPU: the last pass recorded.
pub(crate) fn never_submitted(last: &str) -> String {
    format!("{last}, the last pass recorded; the submission never reached the GPU")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_unwritten_slot_names_the_pass() {
        let passes = ["gbuffer", "ssao", "ao_blur", "deferred", "tonemap"];
        let mut slots = vec![0u32; SLOTS];
        let d = describe(&passes, &slots).unwrap();
        assert_eq!(d, "gbuffer, dispatch 1 of 5: running or next to run on the GPU; 0 finished");
        slots[0] = 1;
        slots[1] = 2;
        let d = describe(&passes, &slots).unwrap();
        assert_eq!(d, "ao_blur, dispatch 3 of 5: running or next to run on the GPU; 2 finished");
        // A later slot written out of order (it cannot be) does not skip the gap.
        slots[3] = 4;
        assert!(describe(&passes, &slots).unwrap().starts_with("ao_blur, dispatch 3"));
        slots[2] = 3;
        slots[4] = 5;
        let d = describe(&passes, &slots).unwrap();
        assert_eq!(d, "tonemap, the last of 5 dispatches: all finished on the GPU");
        assert_eq!(describe(&[], &slots), None);
    }

    #[test]
    fn dispatches_past_the_cap_are_counted_not_tracked() {
        let passes = vec!["pathtrace"; SLOTS + 10];
        let mut slots: Vec<u32> = (1..=SLOTS as u32).collect();
        let d = describe(&passes, &slots).unwrap();
        assert!(d.contains("dispatch 266 of 266") && d.contains("first 256 finished"), "{d}");
        slots[100] = 0;
        let d = describe(&passes, &slots).unwrap();
        assert!(d.starts_with("pathtrace, dispatch 101 of 266: running"), "{d}");
    }
}
