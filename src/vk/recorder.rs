//! Recording into one command buffer with the barriers derived, not placed by hand.
//!
//! Every operation that touches memory (a kernel's dispatch, a fill, an update) names the
//! resources it uses and how ([`Use`]); before it, [`Recorder`] records one global memory barrier
//! exactly when one of them has an earlier access the operation must wait for: a write not yet
//! visible to this use (read after write, write after write) or a read not yet ordered before
//! this write (write after read). A kernel's uses come from its interface (each binding's
//! declared access, [`crate::gpu::kernel::Pipeline`]), so a pass states what it reads and writes
//! once, where the kernel does. The validation layer's synchronization checks, on in every test,
//! report a barrier missed.
//!
//! Images stay in `GENERAL` layout while recorded (their transitions are [`super::Image`]'s), so
//! memory barriers suffice; resources are told apart by their Vulkan handle (an image by its
//! view, a texel buffer by its buffer).

use super::{Buffer, Context, Descriptor};
use crate::error::Result;
use ash::vk;
use std::collections::HashMap;

/// A resource the recorder tracks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Resource {
    /// A buffer (storage or texel).
    Buffer(vk::Buffer),
    /// A storage image, by its view.
    Image(vk::ImageView),
}

impl Resource {
    /// The resource a descriptor binds.
    pub fn of(descriptor: &Descriptor<'_>) -> Self {
        match descriptor {
            Descriptor::Buffer(b) => Resource::Buffer(b.raw),
            Descriptor::StorageImage(i) => Resource::Image(i.view),
            Descriptor::StorageView(view) => Resource::Image(*view),
            Descriptor::Texels(t) => Resource::Buffer(t.buffer.raw),
        }
    }
}

/// How an operation uses a resource.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Use {
    /// A kernel reads it.
    ComputeRead,
    /// A kernel writes it (and may read it).
    ComputeWrite,
    /// An indirect dispatch reads its workgroup counts from it.
    IndirectRead,
    /// A copy reads it.
    TransferRead,
    /// A copy, fill or update writes it.
    TransferWrite,
}

/// Pipeline stages and memory accesses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
struct Scope {
    stages: vk::PipelineStageFlags2,
    access: vk::AccessFlags2,
}

impl Scope {
    fn union(self, other: Scope) -> Scope {
        Scope { stages: self.stages | other.stages, access: self.access | other.access }
    }

    fn contains(self, other: Scope) -> bool {
        self.stages.contains(other.stages) && self.access.contains(other.access)
    }

    fn is_empty(self) -> bool {
        self.stages.is_empty()
    }
}

impl Use {
    fn scope(self) -> Scope {
        use vk::{AccessFlags2 as A, PipelineStageFlags2 as S};
        let (stages, access) = match self {
            Use::ComputeRead => (S::COMPUTE_SHADER, A::SHADER_STORAGE_READ),
            Use::ComputeWrite => (S::COMPUTE_SHADER, A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE),
            Use::IndirectRead => (S::DRAW_INDIRECT, A::INDIRECT_COMMAND_READ),
            Use::TransferRead => (S::ALL_TRANSFER, A::TRANSFER_READ),
            Use::TransferWrite => (S::ALL_TRANSFER, A::TRANSFER_WRITE),
        };
        Scope { stages, access }
    }

    pub(super) fn writes(self) -> bool {
        matches!(self, Use::ComputeWrite | Use::TransferWrite)
    }
}

/// What the recorder knows of one resource.
#[derive(Debug, Clone, Copy, Default)]
struct State {
    /// The stages and accesses that wrote it (all its writes: one barrier covers them).
    written: Scope,
    /// Whom its last write is visible to (after barriers).
    visible: Scope,
    /// The stages that read it since its last write.
    read: vk::PipelineStageFlags2,
    /// The stages its reads are ordered before (by barriers since the last read).
    read_ordered: vk::PipelineStageFlags2,
}

/// Which accesses each resource has had, and the barrier the next operation needs.
#[derive(Debug, Default)]
struct Tracker {
    states: HashMap<Resource, State>,
    /// Every stage and access noted, for the final barrier.
    touched: Scope,
}

impl Tracker {
    /// The barrier (source, destination) an operation with `uses` needs, if any; notes the
    /// barrier as recorded, then the operation's uses.
    fn before(&mut self, uses: &[(Resource, Use)]) -> Option<(Scope, Scope)> {
        let (mut src, mut dst) = (Scope::default(), Scope::default());
        for &(resource, how) in uses {
            let Some(state) = self.states.get(&resource) else { continue };
            let scope = how.scope();
            if !state.written.is_empty() && !state.visible.contains(scope) {
                src = src.union(state.written);
                dst = dst.union(scope);
            }
            if how.writes() && !state.read_ordered.contains(state.read) {
                src.stages |= state.read;
                dst = dst.union(scope);
            }
        }
        let barrier = (!dst.is_empty()).then(|| {
            self.ordered(src, dst);
            (src, dst)
        });
        for &(resource, how) in uses {
            let scope = how.scope();
            self.touched = self.touched.union(scope);
            let state = self.states.entry(resource).or_default();
            if how.writes() {
                state.written = state.written.union(scope);
                state.visible = Scope::default();
                state.read = vk::PipelineStageFlags2::NONE;
                state.read_ordered = vk::PipelineStageFlags2::NONE;
            } else {
                state.read |= scope.stages;
                state.read_ordered = vk::PipelineStageFlags2::NONE;
            }
        }
        barrier
    }

    /// Notes a global memory barrier from `src` to `dst`: the writes it covers become visible
    /// to `dst`, the reads it covers ordered before `dst`'s stages.
    fn ordered(&mut self, src: Scope, dst: Scope) {
        for state in self.states.values_mut() {
            if src.contains(state.written) {
                state.visible = state.visible.union(dst);
            }
            if src.stages.contains(state.read) {
                state.read_ordered |= dst.stages;
            }
        }
    }

    /// The barrier that orders everything noted before any later kernel, copy or indirect
    /// dispatch (none when nothing was noted).
    fn last(&self) -> Option<(Scope, Scope)> {
        if self.touched.is_empty() {
            return None;
        }
        let every =
            [Use::ComputeWrite, Use::ComputeRead, Use::IndirectRead, Use::TransferRead, Use::TransferWrite];
        let after = every.iter().fold(Scope::default(), |s, u| s.union(u.scope()));
        let written = self.states.values().fold(Scope::default(), |s, st| s.union(st.written));
        Some((Scope { stages: self.touched.stages, access: written.access }, after))
    }
}

/// What one [`Recorder`] recorded, for measurement and tests.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RecorderStats {
    /// Operations recorded through it.
    pub operations: u32,
    /// Barriers it derived (the final one of [`Recorder::finish`] included).
    pub barriers: u32,
}

/// A command buffer being recorded, and what it has done to each resource so far.
pub struct Recorder<'a> {
    ctx: &'a Context,
    cmd: vk::CommandBuffer,
    tracker: Tracker,
    /// What the bound kernel's resources are and how it uses them.
    bound: Vec<(Resource, Use)>,
    stats: RecorderStats,
    /// While a frame graph's pass records: the graph's images it may touch.
    pub(super) contract: Option<super::graph::Contract>,
}

impl<'a> Recorder<'a> {
    /// A recorder for `cmd`, in the recording state, whose earlier commands (if any) are already
    /// ordered before it (the host's barrier, or none).
    pub fn new(ctx: &'a Context, cmd: vk::CommandBuffer) -> Self {
        Self {
            ctx,
            cmd,
            tracker: Tracker::default(),
            bound: Vec::new(),
            stats: RecorderStats::default(),
            contract: None,
        }
    }

    /// Runs `record` with a recorder for `cmd` ([`Recorder::new`]) and ends the recording with
    /// [`Recorder::finish`]'s barrier.
    pub fn run<T>(
        ctx: &'a Context,
        cmd: vk::CommandBuffer,
        record: impl FnOnce(&mut Recorder<'_>) -> Result<T>,
    ) -> Result<T> {
        let mut rec = Recorder::new(ctx, cmd);
        let value = record(&mut rec)?;
        rec.finish();
        Ok(value)
    }

    /// The context.
    pub fn ctx(&self) -> &'a Context {
        self.ctx
    }

    /// The command buffer.
    pub fn cmd(&self) -> vk::CommandBuffer {
        self.cmd
    }

    /// What was recorded so far.
    pub fn stats(&self) -> RecorderStats {
        self.stats
    }

    /// Records the barrier an operation with `uses` needs after what came before (none when it
    /// needs none), and notes its uses. Call it right before recording the operation.
    pub fn access(&mut self, uses: &[(Resource, Use)]) {
        if let Some(contract) = &mut self.contract {
            contract.check_all(uses);
        }
        self.note(uses);
    }

    /// [`Recorder::access`] without the frame graph's contract (already checked).
    fn note(&mut self, uses: &[(Resource, Use)]) {
        if let Some(barrier) = self.tracker.before(uses) {
            self.barrier(barrier);
        }
        self.stats.operations += 1;
    }

    /// Records `image`'s start afresh (undefined contents, `GENERAL` layout) after every kernel
    /// and copy recorded before it on the queue: a transient image's first use in a frame.
    pub fn discard(&mut self, image: &super::Image) {
        let every =
            [Use::ComputeWrite, Use::TransferWrite].iter().fold(Scope::default(), |s, u| s.union(u.scope()));
        let after = Use::ComputeWrite.scope();
        super::barrier::image(
            self.ctx,
            self.cmd,
            image.raw,
            vk::ImageLayout::UNDEFINED,
            vk::ImageLayout::GENERAL,
            (every.stages, every.access),
            (after.stages, after.access),
        );
        self.tracker.states.remove(&Resource::Image(image.view));
        self.stats.barriers += 1;
    }

    /// Notes the resources of the kernel about to be bound ([`Recorder::dispatch`] uses them),
    /// or refuses them before anything is recorded: a null image view, or (in a frame graph's
    /// pass) an image of the graph the pass did not declare.
    pub fn bind(&mut self, uses: Vec<(Resource, Use)>) -> Result<()> {
        if uses.iter().any(|(r, _)| *r == Resource::Image(vk::ImageView::null())) {
            return Err(crate::error::Error::Invalid(
                "a kernel's image binding is a null view (an image its frame-graph pass did not declare?)"
                    .into(),
            ));
        }
        if let Some(broken) = self.contract.as_mut().and_then(|c| c.check_all(&uses)) {
            return Err(crate::error::Error::Invalid(format!("the kernel's bindings: {broken}")));
        }
        self.bound = uses;
        Ok(())
    }

    /// Records the barrier a dispatch of the bound kernel needs (reading its workgroup counts
    /// from `indirect`, when given).
    pub fn dispatch(&mut self, indirect: Option<vk::Buffer>) {
        let mut uses = std::mem::take(&mut self.bound);
        let own = uses.len();
        uses.extend(indirect.map(|b| (Resource::Buffer(b), Use::IndirectRead)));
        self.note(&uses);
        uses.truncate(own);
        self.bound = uses;
    }

    /// Records a fill of `buffer` with the 32-bit `value`.
    pub fn fill(&mut self, buffer: &Buffer, value: u32) {
        self.fill_range(buffer, 0, vk::WHOLE_SIZE, value);
    }

    /// Records a fill of `bytes` of `buffer` from `offset` (multiples of 4, or `WHOLE_SIZE`)
    /// with the 32-bit `value` (tracked as a write of the whole buffer).
    pub fn fill_range(&mut self, buffer: &Buffer, offset: u64, bytes: u64, value: u32) {
        self.access(&[(Resource::Buffer(buffer.raw), Use::TransferWrite)]);
        // SAFETY: recording into a command buffer in the recording state; the buffer was made
        // with TRANSFER_DST usage (every umbra buffer is).
        unsafe { self.ctx.device().cmd_fill_buffer(self.cmd, buffer.raw, offset, bytes, value) };
    }

    /// Records an update of `buffer` at `offset` with `bytes` (at most 65,536, a multiple of 4).
    pub fn update(&mut self, buffer: &Buffer, offset: u64, bytes: &[u8]) {
        self.access(&[(Resource::Buffer(buffer.raw), Use::TransferWrite)]);
        // SAFETY: as for `fill`; the caller keeps to vkCmdUpdateBuffer's size rules.
        unsafe { self.ctx.device().cmd_update_buffer(self.cmd, buffer.raw, offset, bytes) };
    }

    /// Records a copy of `regions` of `src` into `dst`.
    pub fn copy(&mut self, src: &Buffer, dst: &Buffer, regions: &[vk::BufferCopy]) {
        self.access(&[
            (Resource::Buffer(src.raw), Use::TransferRead),
            (Resource::Buffer(dst.raw), Use::TransferWrite),
        ]);
        // SAFETY: recording into a command buffer in the recording state; the caller keeps the
        // regions within both buffers (made with TRANSFER_SRC and TRANSFER_DST usage).
        unsafe { self.ctx.device().cmd_copy_buffer(self.cmd, src.raw, dst.raw, regions) };
    }

    /// Ends the recording with one barrier that makes everything it wrote visible to the
    /// kernels, copies and indirect dispatches recorded after it and orders its reads before
    /// their writes (the contract with a host: [`crate::embed`]). Returns what was recorded.
    pub fn finish(mut self) -> RecorderStats {
        if let Some(barrier) = self.tracker.last() {
            self.barrier(barrier);
        }
        log::debug!("recorded {} operations with {} barriers", self.stats.operations, self.stats.barriers);
        self.stats
    }

    fn barrier(&mut self, (src, dst): (Scope, Scope)) {
        super::barrier::memory(self.ctx, self.cmd, (src.stages, src.access), (dst.stages, dst.access));
        self.stats.barriers += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ash::vk::Handle;

    fn buffer(n: u64) -> Resource {
        Resource::Buffer(vk::Buffer::from_raw(n))
    }

    fn image(n: u64) -> Resource {
        Resource::Image(vk::ImageView::from_raw(n))
    }

    #[test]
    fn a_barrier_exactly_where_an_access_waits_for_an_earlier_one() {
        let (a, b, c) = (image(1), image(2), buffer(3));
        let mut t = Tracker::default();
        // Two kernels writing different images need nothing between them.
        assert_eq!(t.before(&[(a, Use::ComputeWrite)]), None);
        assert_eq!(t.before(&[(b, Use::ComputeWrite)]), None);
        // Read after write.
        let (src, dst) =
            t.before(&[(a, Use::ComputeRead), (c, Use::ComputeWrite)]).expect("read after write");
        assert!(src.access.contains(vk::AccessFlags2::SHADER_STORAGE_WRITE));
        assert!(dst.access.contains(vk::AccessFlags2::SHADER_STORAGE_READ));
        // That barrier covered b's write too, and reads after reads need nothing.
        assert_eq!(t.before(&[(b, Use::ComputeRead), (a, Use::ComputeRead)]), None);
        // Write after read: an execution dependency on the reading stage.
        let (src, _) = t.before(&[(a, Use::ComputeWrite)]).expect("write after read");
        assert!(src.stages.contains(vk::PipelineStageFlags2::COMPUTE_SHADER));
        // Write after write.
        assert!(t.before(&[(a, Use::ComputeWrite)]).is_some());
        // c, written before the last two barriers, is visible to kernels but not to an indirect
        // dispatch's read of its counts.
        assert_eq!(t.before(&[(c, Use::ComputeRead)]), None);
        let (_, dst) = t.before(&[(c, Use::IndirectRead)]).expect("indirect read after write");
        assert!(dst.access.contains(vk::AccessFlags2::INDIRECT_COMMAND_READ));
    }

    #[test]
    fn transfers_are_ordered_with_kernels_both_ways() {
        let a = buffer(1);
        let mut t = Tracker::default();
        assert_eq!(t.before(&[(a, Use::TransferWrite)]), None);
        let (src, dst) = t.before(&[(a, Use::ComputeWrite)]).expect("fill then kernel");
        assert!(src.stages.contains(vk::PipelineStageFlags2::ALL_TRANSFER));
        assert!(dst.stages.contains(vk::PipelineStageFlags2::COMPUTE_SHADER));
        let (src, dst) = t.before(&[(a, Use::TransferWrite)]).expect("kernel then fill");
        assert!(src.access.contains(vk::AccessFlags2::SHADER_STORAGE_WRITE));
        assert!(dst.access.contains(vk::AccessFlags2::TRANSFER_WRITE));
        let (src, dst) = t.last().expect("the final barrier");
        assert!(src
            .stages
            .contains(vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::ALL_TRANSFER));
        assert!(dst.access.contains(vk::AccessFlags2::SHADER_STORAGE_READ));
        assert_eq!(Tracker::default().last(), None);
    }
}
