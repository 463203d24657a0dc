//! synchronization2 barriers for the few transitions umbra needs.

use super::Context;
use ash::vk;

/// A global memory barrier from `src` to `dst` (stage, access) pairs.
pub fn memory(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    src: (vk::PipelineStageFlags2, vk::AccessFlags2),
    dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
) {
    let barrier = [vk::MemoryBarrier2::default()
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)];
    // SAFETY: recording into a command buffer in the recording state.
    unsafe {
        ctx.device().cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&barrier))
    };
}

const COMPUTE_RW: (vk::PipelineStageFlags2, vk::AccessFlags2) = (
    vk::PipelineStageFlags2::COMPUTE_SHADER,
    vk::AccessFlags2::from_raw(
        vk::AccessFlags2::SHADER_STORAGE_READ.as_raw()
            | vk::AccessFlags2::SHADER_STORAGE_WRITE.as_raw()
            | vk::AccessFlags2::SHADER_SAMPLED_READ.as_raw(),
    ),
);
/// A kernel's reads and writes and an indirect dispatch's read of its workgroup counts.
const COMPUTE_INDIRECT: (vk::PipelineStageFlags2, vk::AccessFlags2) = (
    vk::PipelineStageFlags2::from_raw(
        vk::PipelineStageFlags2::COMPUTE_SHADER.as_raw() | vk::PipelineStageFlags2::DRAW_INDIRECT.as_raw(),
    ),
    vk::AccessFlags2::from_raw(COMPUTE_RW.1.as_raw() | vk::AccessFlags2::INDIRECT_COMMAND_READ.as_raw()),
);
const TRANSFER_WRITE: (vk::PipelineStageFlags2, vk::AccessFlags2) =
    (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_WRITE);
const TRANSFER_READ: (vk::PipelineStageFlags2, vk::AccessFlags2) =
    (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_READ);

/// Kernel writes visible to the next kernel's reads and writes.
pub fn compute_to_compute(ctx: &Context, cmd: vk::CommandBuffer) {
    memory(ctx, cmd, COMPUTE_RW, COMPUTE_RW);
}

/// Kernel writes visible to the next kernel's reads and writes and to an indirect dispatch's
/// read of its workgroup counts.
pub fn compute_to_indirect(ctx: &Context, cmd: vk::CommandBuffer) {
    memory(ctx, cmd, COMPUTE_RW, COMPUTE_INDIRECT);
}

/// Copies (uploads, clears) visible to kernels and to an indirect dispatch's read of its
/// workgroup counts.
pub fn transfer_to_indirect(ctx: &Context, cmd: vk::CommandBuffer) {
    memory(ctx, cmd, TRANSFER_WRITE, COMPUTE_INDIRECT);
}

/// Copies (uploads, clears) visible to kernels.
pub fn transfer_to_compute(ctx: &Context, cmd: vk::CommandBuffer) {
    memory(ctx, cmd, TRANSFER_WRITE, COMPUTE_RW);
}

/// Kernel writes visible to a copy (readback).
pub fn compute_to_transfer(ctx: &Context, cmd: vk::CommandBuffer) {
    memory(ctx, cmd, COMPUTE_RW, TRANSFER_READ);
}

/// Copy results visible to the host after the submission's fence.
pub fn transfer_to_host(ctx: &Context, cmd: vk::CommandBuffer) {
    memory(ctx, cmd, TRANSFER_WRITE, (vk::PipelineStageFlags2::HOST, vk::AccessFlags2::HOST_READ));
}

/// An image layout transition with explicit stages and accesses on both sides.
pub fn image(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    old: vk::ImageLayout,
    new: vk::ImageLayout,
    src: (vk::PipelineStageFlags2, vk::AccessFlags2),
    dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
) {
    let barrier = [vk::ImageMemoryBarrier2::default()
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)
        .old_layout(old)
        .new_layout(new)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(color_range())];
    // SAFETY: recording into a command buffer in the recording state.
    unsafe {
        ctx.device()
            .cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&barrier))
    };
}

/// The whole colour aspect of a single-mip, single-layer image.
pub fn color_range() -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .level_count(1)
        .layer_count(1)
}

/// Stage/access pairs, for callers of [`image()`] and [`memory()`].
pub mod access {
    use ash::vk;
    /// Nothing before (undefined contents).
    pub const NONE: (vk::PipelineStageFlags2, vk::AccessFlags2) =
        (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE);
    /// Compute kernels reading or writing storage resources.
    pub const COMPUTE_RW: (vk::PipelineStageFlags2, vk::AccessFlags2) = super::COMPUTE_RW;
    /// A copy reading.
    pub const TRANSFER_READ: (vk::PipelineStageFlags2, vk::AccessFlags2) = super::TRANSFER_READ;
    /// A copy or clear writing.
    pub const TRANSFER_WRITE: (vk::PipelineStageFlags2, vk::AccessFlags2) = super::TRANSFER_WRITE;
}
