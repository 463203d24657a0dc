//! The display transform on the GPU (`spirv/tonemap.comp`): a linear `R32G32B32A32_SFLOAT` image
//! × exposure, through a [`ToneCurve`], sRGB-encoded into an `R8G8B8A8_UNORM` image. Both images
//! in `GENERAL` layout; a compute-to-compute barrier follows. [`crate::tonemap`] is its CPU twin.

use crate::error::Result;
use crate::gpu::layout::TonemapParams;
pub use crate::tonemap::ToneCurve;
use crate::vk::{barrier, raw, ComputePipeline, Context, Descriptor, PipelineDesc};

/// `tonemap.comp`.
pub struct TonemapPass {
    pipeline: ComputePipeline,
}

impl TonemapPass {
    /// Workgroup size of the kernel.
    pub const LOCAL: [u32; 3] = [8, 8, 1];

    /// Builds the pipeline.
    pub fn new(ctx: &Context) -> Result<Self> {
        let pipeline = ComputePipeline::new(
            ctx,
            "tonemap",
            &PipelineDesc {
                bindings: &[raw::DescriptorType::STORAGE_IMAGE; 2],
                push_constant_size: std::mem::size_of::<TonemapParams>() as u32,
                specialization: &[],
            },
        )?;
        Ok(Self { pipeline })
    }

    /// Records `dst = sRGB(curve(src × 2^stops))` over `size` pixels and a barrier after it:
    /// `src` an `R32G32B32A32_SFLOAT` and `dst` an `R8G8B8A8_UNORM` storage image, both in
    /// `GENERAL` layout. Never submits.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        ctx: &Context,
        cmd: raw::CommandBuffer,
        src: raw::ImageView,
        dst: raw::ImageView,
        (w, h): (u32, u32),
        exposure_stops: f32,
        curve: ToneCurve,
    ) -> Result<()> {
        self.pipeline.record(
            cmd,
            &[Descriptor::StorageView(src), Descriptor::StorageView(dst)],
            &TonemapParams { size: [w, h], exposure: exposure_stops.exp2(), curve: curve.code() },
            [w, h, 1],
            Self::LOCAL,
        )?;
        barrier::compute_to_compute(ctx, cmd);
        Ok(())
    }
}
