//! The display transform on the GPU (`spirv/tonemap.comp`): a linear `R32G32B32A32_SFLOAT` image
//! × exposure, through a [`ToneCurve`], sRGB-encoded into an `R8G8B8A8_UNORM` image. Both images
//! in `GENERAL` layout. [`crate::color`] is its CPU twin.

pub use crate::color::ToneCurve;
use crate::error::Result;
use crate::gpu::kernels::tonemap;
use crate::gpu::layout::TonemapParams;
use crate::gpu::Pipeline;
use crate::vk::{raw, Context, Recorder};

/// `tonemap.comp`.
pub struct TonemapPass {
    pipeline: Pipeline<tonemap::Kernel>,
}

impl TonemapPass {
    /// Builds the pipeline.
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Self { pipeline: Pipeline::plain(ctx)? })
    }

    /// Records `dst = sRGB(curve(src × 2^stops))` over `size` pixels:
    /// `src` an `R32G32B32A32_SFLOAT` and `dst` an `R8G8B8A8_UNORM` storage image, both in
    /// `GENERAL` layout. Never submits.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        src: raw::ImageView,
        dst: raw::ImageView,
        (w, h): (u32, u32),
        exposure_stops: f32,
        curve: ToneCurve,
    ) -> Result<()> {
        self.pipeline.record(
            rec,
            &tonemap::Resources { src: &src, dst: &dst },
            &TonemapParams { size: [w, h], exposure: exposure_stops.exp2(), curve: curve.code() },
            [w, h, 1],
        )?;
        Ok(())
    }
}
