//! Ambient occlusion over a G-buffer: screen-space (`spirv/ssao.comp`, `spirv/gtao.comp`), their
//! depth-aware blur (`spirv/ao_blur.comp`) and ray-traced (`spirv/rtao.comp`), the ground truth
//! both approximate.
//!
//! Both estimate one quantity: **AO(p) = (1/π) ∫ V_r(p, ω) cos θ dω**, the cosine-weighted
//! fraction of the hemisphere around the shading normal whose rays leave p without meeting
//! geometry within the radius r (1 = unoccluded, 0 = fully occluded).
//!
//! - **RTAO** casts `samples` cosine-distributed any-hit rays of length r through the BVH (origin
//!   offset off the geometric surface as shadow rays are); its value is the fraction that escape,
//!   unbiased with variance AO(1 − AO)/samples.
//! - **SSAO** sees only the G-buffer: `samples` directions of a fixed cosine-weighted kernel,
//!   rotated about the normal per pixel by a 4×4 tiled pattern (which [`AoBlurPass`] averages
//!   away), each marched at `steps` points at distances r·f² (more near p, the last at r). A point
//!   is occluded when it lies behind the surface seen at its pixel (depth read as the front of
//!   solid matter, tested against that surface's plane), unless that surface is more than r in
//!   front of p (the range check). Points that project **off screen**, behind the camera or onto
//!   the background count as **unoccluded** (the usual choice; it brightens AO at the screen's
//!   edges and misses occluders outside the frustum, two of SSAO's failure modes, with thin
//!   objects read as thick the third).
//!
//! - **GTAO** (ground-truth-based AO, Jimenez et al. 2016, with XeGTAO's sampling) also sees
//!   only the G-buffer: per pixel `samples` slices (planes through the view vector), in each the
//!   highest depth-buffer point within r on either side of the pixel (`steps` points a side),
//!   and the cosine-weighted visible arc between those horizons in closed form. Exact where the
//!   depth buffer is a height field of the occluders; it shares SSAO's three failure modes, reads
//!   24 depths a pixel by default against SSAO's up to 64, and runs at full or half resolution
//!   ([`AoResolution`]).
//!
//! Every pass reads G-buffer views (umbra's or a host's, formats of [`super::gbuffer`]) and writes
//! an `R32_SFLOAT` storage image in `GENERAL` layout and never submits.

use super::gbuffer::GBufferViews;
use crate::error::{Error, Result};
use crate::gpu::kernels::{ao_blur, gtao, rtao, ssao};
use crate::gpu::layout::{AoBlurParams, AoParams, GpuCamera};
use crate::gpu::scene::GpuScene;
use crate::gpu::{Pipeline, SceneFeatures};
use crate::scene::Camera;
use crate::vk::{raw, Context, Recorder};

/// Which ambient occlusion estimator runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AoMethod {
    /// Screen-space AO from the G-buffer ([`SsaoPass`]).
    #[default]
    Ssao,
    /// Ground-truth-based AO from the G-buffer ([`GtaoPass`]).
    Gtao,
    /// Ray-traced AO through the BVH ([`RtaoPass`]), the ground truth.
    Rtao,
}

impl AoMethod {
    /// The method's name on the command line and in benchmark records.
    pub fn name(self) -> &'static str {
        match self {
            Self::Ssao => "ssao",
            Self::Gtao => "gtao",
            Self::Rtao => "rtao",
        }
    }
}

/// Where the AO is computed: at every G-buffer pixel, or at one pixel of each 2×2 block and then
/// upsampled by the depth-aware blur ([`AoBlurPass`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AoResolution {
    /// Every pixel.
    #[default]
    Full,
    /// One pixel in four (GTAO only).
    Half,
}

impl AoResolution {
    /// G-buffer pixels per AO texel along each axis.
    pub fn scale(self) -> u32 {
        match self {
            Self::Full => 1,
            Self::Half => 2,
        }
    }

    /// The AO image's size for a G-buffer of `size`.
    pub fn ao_size(self, size: (u32, u32)) -> (u32, u32) {
        let s = self.scale();
        (size.0.div_ceil(s), size.1.div_ceil(s))
    }
}

/// What the AO passes compute.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AoSettings {
    /// The estimator.
    pub method: AoMethod,
    /// Where it runs (full or half resolution).
    pub resolution: AoResolution,
    /// SSAO: kernel directions per pixel; GTAO: slices per pixel; RTAO: rays per pixel.
    pub samples: u32,
    /// The AO radius r in world units (metres): occluders farther away do not count.
    pub radius: f32,
    /// Blur the result with [`AoBlurPass`] (removes SSAO's 4×4 rotation pattern).
    pub blur: bool,
    /// SSAO: points marched along each direction; GTAO: points each side of the pixel per slice.
    pub steps: u32,
    /// SSAO: how far (world units) a point must be behind a surface's plane to count as occluded.
    pub bias: f32,
    /// GTAO: the fraction of the radius over which an occluder's weight fades to 0 at the radius
    /// (0: a hard cut-off at the radius, as RTAO's rays have).
    pub falloff: f32,
    /// Frame index: decorrelates RTAO's rays (and rotates SSAO's kernel) between frames.
    pub frame: u32,
    /// Seed of the random numbers.
    pub seed: u32,
}

impl Default for AoSettings {
    fn default() -> Self {
        Self {
            method: AoMethod::Ssao,
            resolution: AoResolution::Full,
            samples: 16,
            radius: 0.5,
            blur: true,
            steps: 4,
            bias: 1e-3,
            falloff: Self::GTAO_FALLOFF,
            frame: 0,
            seed: 0,
        }
    }
}

impl AoSettings {
    /// GTAO's default slices per pixel. XeGTAO's "high" preset is 3 slices × 3 steps, with
    /// its falloff (0.615 of the radius), a radius multiplier (1.457) and a final power (2.2)
    /// making up for what the soft falloff misses; against RTAO's hard radius (`tests/ao.rs`' room,
    /// mean |GTAO − RTAO|) that preset without its artistic factors measured 0.128, 3 × 3 with a hard
    /// cut-off 0.060, and with steps spaced linearly instead of quadratically 0.038; 2 × 6 linear
    /// measured 0.024 for 24 depth reads, 0.023 once divided by the open hemisphere's value and
    /// 0.022 with the solid behind a sample beyond r counted (`gtao.comp`) (SSAO: 0.021 for up
    /// to 64 reads; GTAO with 16 × 16 as XeGTAO spaces them, 0.022).
    pub const GTAO_SLICES: u32 = 2;
    /// GTAO's default steps each side per slice (see [`AoSettings::GTAO_SLICES`]).
    pub const GTAO_STEPS: u32 = 6;
    /// GTAO's default falloff: none, a hard cut-off at the radius as RTAO's rays have (see
    /// [`AoSettings::GTAO_SLICES`]).
    pub const GTAO_FALLOFF: f32 = 0.0;

    /// The defaults of `method`: SSAO's 16 directions × 4 steps, GTAO's
    /// [`AoSettings::GTAO_SLICES`] × [`AoSettings::GTAO_STEPS`], RTAO's 16 rays.
    pub fn of(method: AoMethod) -> Self {
        match method {
            AoMethod::Gtao => {
                Self { method, samples: Self::GTAO_SLICES, steps: Self::GTAO_STEPS, ..Self::default() }
            }
            _ => Self { method, ..Self::default() },
        }
    }

    /// Checks the settings: at least one sample and one step, a finite positive radius, a finite
    /// non-negative bias.
    pub fn validate(&self) -> Result<()> {
        if self.samples == 0 || self.steps == 0 {
            return Err(Error::Invalid(format!(
                "ambient occlusion needs at least one sample and one step (got {} samples, {} steps)",
                self.samples, self.steps
            )));
        }
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return Err(Error::Invalid(format!("ambient occlusion radius {} must be positive", self.radius)));
        }
        if !(self.bias.is_finite() && self.bias >= 0.0) {
            return Err(Error::Invalid(format!("SSAO bias {} must be non-negative", self.bias)));
        }
        if !(0.0..=1.0).contains(&self.falloff) {
            return Err(Error::Invalid(format!("GTAO falloff {} must lie in [0, 1]", self.falloff)));
        }
        if self.resolution == AoResolution::Half {
            if self.method != AoMethod::Gtao {
                return Err(Error::Invalid(format!(
                    "half-resolution ambient occlusion is GTAO's; {} runs at full resolution",
                    self.method.name()
                )));
            }
            if !self.blur {
                return Err(Error::Invalid(
                    "half-resolution ambient occlusion needs its blur, which is also its upsample".into(),
                ));
            }
        }
        Ok(())
    }
}

/// The push constants of the AO kernels (SSAO, GTAO, RTAO) for `camera` over a G-buffer of
/// `size`.
pub fn ao_params(camera: &Camera, size: (u32, u32), settings: &AoSettings) -> AoParams {
    AoParams {
        camera: GpuCamera::new(camera, size),
        radius: settings.radius,
        bias: settings.bias,
        size: [size.0, size.1],
        frame: settings.frame,
        seed: settings.seed,
        samples: settings.samples,
        steps: settings.steps,
        falloff: settings.falloff,
        scale: settings.resolution.scale(),
        ..Default::default()
    }
}

/// `ssao.comp`: screen-space AO from depth and normals.
pub struct SsaoPass {
    pipeline: Pipeline<ssao::Kernel>,
}

impl SsaoPass {
    /// Builds the pipeline.
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Self { pipeline: Pipeline::plain(ctx)? })
    }

    /// Records the pass: G-buffer depth and normal in, `output` (`R32_SFLOAT`, `GENERAL`, the
    /// G-buffer's size) written. Never submits.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        gbuffer: &GBufferViews,
        output: raw::ImageView,
        params: &AoParams,
    ) -> Result<()> {
        self.pipeline.record(
            rec,
            &ssao::Resources { gb: gbuffer, out_ao: &output },
            params,
            [gbuffer.size.0, gbuffer.size.1, 1],
        )?;
        Ok(())
    }
}

/// `gtao.comp`: ground-truth-based AO from depth and normals, at full or half resolution.
pub struct GtaoPass {
    pipeline: Pipeline<gtao::Kernel>,
}

impl GtaoPass {
    /// Builds the pipeline.
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Self { pipeline: Pipeline::plain(ctx)? })
    }

    /// Records the pass: G-buffer depth and normal in, `output` (`R32_SFLOAT`, `GENERAL`, at
    /// least [`AoResolution::ao_size`] of the G-buffer's size; the texels beyond are left as
    /// they were) written. Never submits.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        gbuffer: &GBufferViews,
        output: raw::ImageView,
        params: &AoParams,
    ) -> Result<()> {
        let s = params.scale.max(1);
        self.pipeline.record(
            rec,
            &gtao::Resources { gb: gbuffer, out_ao: &output },
            params,
            [gbuffer.size.0.div_ceil(s), gbuffer.size.1.div_ceil(s), 1],
        )?;
        Ok(())
    }
}

/// `ao_blur.comp`: a bilateral 4×4 blur of an AO image, weighted by plane distance and normals.
pub struct AoBlurPass {
    pipeline: Pipeline<ao_blur::Kernel>,
}

impl AoBlurPass {
    /// Sigma of the plane-distance weight, as a fraction of the centre's view depth.
    pub const PLANE_SIGMA: f32 = 0.02;

    /// Builds the pipeline.
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Self { pipeline: Pipeline::plain(ctx)? })
    }

    /// The push constants for `camera` over an image of `size`, reading AO computed at
    /// `resolution`.
    pub fn params(camera: &Camera, size: (u32, u32), resolution: AoResolution) -> AoBlurParams {
        AoBlurParams {
            camera: GpuCamera::new(camera, size),
            depth_sigma: Self::PLANE_SIGMA,
            size: [size.0, size.1],
            scale: resolution.scale(),
            ..Default::default()
        }
    }

    /// Records the blur of `input` into `output` (both `R32_SFLOAT`, `GENERAL`, distinct images;
    /// `output` the G-buffer's size, `input` the AO's: [`AoResolution::ao_size`]). Never submits.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        gbuffer: &GBufferViews,
        input: raw::ImageView,
        output: raw::ImageView,
        params: &AoBlurParams,
    ) -> Result<()> {
        self.pipeline.record(
            rec,
            &ao_blur::Resources { ao_in: &input, gb: gbuffer, out_ao: &output },
            params,
            [gbuffer.size.0, gbuffer.size.1, 1],
        )?;
        Ok(())
    }
}

/// `rtao.comp`: ray-traced AO, the ground truth.
pub struct RtaoPass {
    pipeline: Pipeline<rtao::Kernel>,
}

impl RtaoPass {
    /// Builds the pipeline for `scene` (specialised for its textures and alpha-tested materials:
    /// masked and blended surfaces occlude as the path tracer sees them).
    pub fn new(ctx: &Context, scene: &GpuScene) -> Result<Self> {
        Self::for_features(ctx, &scene.features())
    }

    /// [`RtaoPass::new`] for a scene with `features` (before it is uploaded).
    pub fn for_features(ctx: &Context, features: &SceneFeatures) -> Result<Self> {
        Ok(Self { pipeline: Pipeline::new(ctx, &rtao::Spec::default(), Some(features))? })
    }

    /// Rays per pixel in one dispatch: llvmpipe breaks every loop of an invocation after 65,535
    /// loop iterations in all, and one ray through a large BVH can take a few hundred.
    pub const RAYS_PER_DISPATCH: u32 = 32;

    /// Records the pass: the scene's BVH and the G-buffer's depth, normal and material (for the
    /// geometric normal) in, `output` (`R32_SFLOAT`, `GENERAL`) written. The rays go in batches of [`RtaoPass::RAYS_PER_DISPATCH`],
    /// one dispatch each. Never submits.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        gbuffer: &GBufferViews,
        output: raw::ImageView,
        params: &AoParams,
    ) -> Result<()> {
        let resources = rtao::Resources { scene, gb: gbuffer, out_ao: &output };
        // The pipeline and resources once; per batch only the push constants change.
        let p = &self.pipeline;
        p.bind(rec, &resources)?;
        let rays = params.samples.max(1);
        for first in (0..rays).step_by(Self::RAYS_PER_DISPATCH as usize) {
            let mut batch = *params;
            batch.first_ray = first;
            batch.batch_rays = Self::RAYS_PER_DISPATCH.min(rays - first);
            p.push_constants(rec, &batch)?;
            p.dispatch(rec, [gbuffer.size.0, gbuffer.size.1, 1])?;
        }
        Ok(())
    }
}
