//! Embedding umbra in a host Vulkan engine.
//!
//! The host keeps its instance, device, queue, allocator, images and command buffers; umbra
//! records its passes into the host's command buffer and never submits it.
//!
//! ```text
//! let ctx = Context::from_host(HostDevice { entry, instance, physical_device, device, queue,
//!                                           queue_family_index, allocator: Some(allocator) })?;
//! let mut renderer = Renderer::new(&ctx, &scene)?;          // uploads the scene once
//! // per frame, inside the host's command buffer:
//! renderer.record_gbuffer(cmd, &camera, &gbuffer_views)?;   // or the host writes its own
//! let ao = renderer.record_ssao(cmd, &camera, &gbuffer_views, ao_view, ao_blur_view, &ao_settings)?;
//! renderer.record_lighting(cmd, &camera, &gbuffer_views, hdr_view, Some(ao), &lighting)?;
//! renderer.record_tonemap(cmd, hdr_view, ldr_view, size, 0.0, ToneCurve::KhronosPbrNeutral)?;
//! // or progressive path tracing, a few samples per frame, resolved into the host's image:
//! renderer.record_path_samples(cmd, &camera, &target, &path_settings, first_sample, count)?;
//! renderer.record_path_resolve(cmd, &target, hdr_view)?;
//! ```
//!
//! Contract:
//! - The device was created with Vulkan 1.3, `synchronization2` and `VK_KHR_push_descriptor`
//!   ([`crate::vk::HostDevice`]). umbra allocates its own buffers from the host's
//!   `gpu-allocator` (shared as `Arc<Mutex<Allocator>>`) and frees them when dropped; it never
//!   destroys a host object.
//! - Images passed in are storage images in `GENERAL` layout with the formats the pass
//!   documents ([`crate::passes::gbuffer`] for a G-buffer). Before a `record_*` call, the host
//!   makes its writes to them visible to compute-shader reads (for its own compute kernels, a
//!   compute → compute memory barrier). Each `record_*` call ends with a compute → compute
//!   barrier (`SHADER_STORAGE_WRITE` → `SHADER_STORAGE_READ | WRITE`); a host that reads the output
//!   in another stage adds its own barrier from `COMPUTE_SHADER`/`SHADER_STORAGE_WRITE`. Layouts
//!   are never changed.
//! - `record_*` binds its own pipeline, push descriptors and push constants: the host re-binds
//!   its own state afterwards.
//! - No global state: two `Renderer`s (on one device or two) are independent.
//! - [`Renderer::update_scene`] (materials and lights changed) and construction upload through
//!   the context's queue and wait; call them while no command buffer using the renderer is
//!   pending (after the host's frame fence).

use crate::error::{Error, Result};
use crate::gpu::scene::GpuScene;
use crate::passes::ao::{AoBlurPass, AoSettings, RtaoPass, SsaoPass};
use crate::passes::deferred::{DeferredPass, LightingSettings};
use crate::passes::gbuffer::{GBufferPass, GBufferViews};
use crate::passes::ibl::{IblResources, IblSettings};
use crate::passes::pathtrace::{Heuristic, Microfacet, PathSettings, PathTarget, PathTracePass, ResolvePass};
use crate::passes::tonemap::{ToneCurve, TonemapPass};
use crate::scene::{Camera, Scene};
use crate::vk::{raw, Context};

/// umbra's passes and one scene on a (host's) device.
pub struct Renderer {
    ctx: Context,
    scene: GpuScene,
    gbuffer: GBufferPass,
    deferred: DeferredPass,
    ibl: IblResources,
    ssao: SsaoPass,
    ao_blur: AoBlurPass,
    rtao: RtaoPass,
    tonemap: TonemapPass,
    path: PathTracePass,
    path_options: (Microfacet, Heuristic),
    resolve: ResolvePass,
}

impl Renderer {
    /// Builds the BVH, uploads the scene and creates the pipelines it needs.
    pub fn new(ctx: &Context, scene: &Scene) -> Result<Self> {
        let gpu_scene = GpuScene::upload(ctx, scene)?;
        Ok(Self {
            gbuffer: GBufferPass::new(ctx, &gpu_scene)?,
            deferred: DeferredPass::new(ctx, &gpu_scene)?,
            ibl: IblResources::build(ctx, &gpu_scene, &IblSettings::default())?,
            ssao: SsaoPass::new(ctx)?,
            ao_blur: AoBlurPass::new(ctx)?,
            rtao: RtaoPass::new(ctx, &gpu_scene)?,
            tonemap: TonemapPass::new(ctx)?,
            path: PathTracePass::for_scene(ctx, &gpu_scene, Microfacet::Ggx, Heuristic::Power)?,
            path_options: (Microfacet::Ggx, Heuristic::Power),
            resolve: ResolvePass::new(ctx)?,
            scene: gpu_scene,
            ctx: ctx.clone(),
        })
    }

    /// The scene on the GPU.
    pub fn scene(&self) -> &GpuScene {
        &self.scene
    }

    /// Takes changed materials, textures or lights of `scene` (same geometry) without rebuilding
    /// the BVH, and re-specialises the lighting pipeline for them.
    pub fn update_scene(&mut self, scene: &Scene) -> Result<()> {
        self.scene.update(&self.ctx, scene)?;
        self.gbuffer = GBufferPass::new(&self.ctx, &self.scene)?;
        self.deferred = DeferredPass::new(&self.ctx, &self.scene)?;
        self.rtao = RtaoPass::new(&self.ctx, &self.scene)?;
        self.path =
            PathTracePass::for_scene(&self.ctx, &self.scene, self.path_options.0, self.path_options.1)?;
        Ok(())
    }

    /// Chooses the path tracer's microfacet model and MIS heuristic (GGX and the power
    /// heuristic by default); rebuilds its pipeline.
    pub fn set_path_tracer(&mut self, microfacet: Microfacet, heuristic: Heuristic) -> Result<()> {
        self.path = PathTracePass::for_scene(&self.ctx, &self.scene, microfacet, heuristic)?;
        self.path_options = (microfacet, heuristic);
        Ok(())
    }

    /// Accumulation buffers for progressive path tracing at `size` (owned by umbra, freed on
    /// drop).
    pub fn path_target(&self, size: (u32, u32)) -> Result<PathTarget> {
        PathTarget::new(&self.ctx, size)
    }

    /// Records path-traced samples `first .. first + count` into `target` (sample 0 restarts
    /// the running mean; a moved camera or changed scene restarts at 0). `settings.size` must be
    /// the target's; its microfacet and heuristic those of [`Self::set_path_tracer`].
    pub fn record_path_samples(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        target: &PathTarget,
        settings: &PathSettings,
        first: u32,
        count: u32,
    ) -> Result<()> {
        if settings.size != target.size {
            return Err(Error::Invalid(format!(
                "path settings are for {:?} but the target is {:?}",
                settings.size, target.size
            )));
        }
        if (settings.microfacet, settings.heuristic) != self.path_options {
            return Err(Error::Invalid(format!(
                "the renderer's path tracer is built for {:?}; call set_path_tracer for {:?}",
                self.path_options,
                (settings.microfacet, settings.heuristic)
            )));
        }
        let mut params = PathTracePass::params(&self.scene, camera, settings);
        for sample in first..first + count {
            params.sample_index = sample;
            self.path.record(&self.ctx, cmd, &self.scene, target, &params)?;
        }
        Ok(())
    }

    /// Records the copy of `target`'s running mean into `output`: the host's
    /// `R32G32B32A32_SFLOAT` storage image of the target's size, in `GENERAL` layout (then, like
    /// every `record_*`, a compute → compute barrier).
    pub fn record_path_resolve(
        &self,
        cmd: raw::CommandBuffer,
        target: &PathTarget,
        output: raw::ImageView,
    ) -> Result<()> {
        self.resolve.record(&self.ctx, cmd, target, output)
    }

    /// Records umbra's ray-cast G-buffer for `camera` into `target`.
    pub fn record_gbuffer(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        target: &GBufferViews,
    ) -> Result<()> {
        let params = GBufferPass::params(camera, target.size);
        self.gbuffer.record(&self.ctx, cmd, &self.scene, target, &params)
    }

    /// Records SSAO of `gbuffer` (umbra's or the host's) into `raw_ao` and, when `settings.blur`,
    /// its depth-aware blur into `blurred`: both `R32_SFLOAT` storage images of the G-buffer's
    /// size in `GENERAL` layout (1 = unoccluded). Returns the view holding the result, for
    /// [`Self::record_lighting`].
    pub fn record_ssao(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        gbuffer: &GBufferViews,
        raw_ao: raw::ImageView,
        blurred: raw::ImageView,
        settings: &AoSettings,
    ) -> Result<raw::ImageView> {
        settings.validate()?;
        let params = SsaoPass::params(camera, gbuffer.size, settings);
        self.ssao.record(&self.ctx, cmd, gbuffer, raw_ao, &params)?;
        if !settings.blur {
            return Ok(raw_ao);
        }
        let blur_params = AoBlurPass::params(camera, gbuffer.size);
        self.ao_blur.record(&self.ctx, cmd, gbuffer, raw_ao, blurred, &blur_params)?;
        Ok(blurred)
    }

    /// Records ray-traced ambient occlusion of `gbuffer` (SSAO's ground truth: `settings.samples`
    /// rays of length `settings.radius` per pixel) into `output`, an `R32_SFLOAT` storage image of
    /// the G-buffer's size in `GENERAL` layout.
    pub fn record_rtao(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        gbuffer: &GBufferViews,
        output: raw::ImageView,
        settings: &AoSettings,
    ) -> Result<()> {
        settings.validate()?;
        let params = RtaoPass::params(camera, gbuffer.size, settings);
        self.rtao.record(&self.ctx, cmd, &self.scene, gbuffer, output, &params)
    }

    /// Records deferred lighting of `gbuffer` (umbra's or the host's own) seen from `camera` into
    /// `output` (`R32G32B32A32_SFLOAT`, the G-buffer's size).
    pub fn record_lighting(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        gbuffer: &GBufferViews,
        output: raw::ImageView,
        ao: Option<raw::ImageView>,
        settings: &LightingSettings,
    ) -> Result<()> {
        settings.validate()?;
        let params = DeferredPass::params(&self.scene, camera, gbuffer.size, settings);
        self.deferred.record(&self.ctx, cmd, &self.scene, gbuffer, output, &self.ibl, ao, &params)
    }

    /// Records the display transform of `src` (`R32G32B32A32_SFLOAT`) into `dst`
    /// (`R8G8B8A8_UNORM`, sRGB-encoded values).
    pub fn record_tonemap(
        &self,
        cmd: raw::CommandBuffer,
        src: raw::ImageView,
        dst: raw::ImageView,
        size: (u32, u32),
        exposure_stops: f32,
        curve: ToneCurve,
    ) -> Result<()> {
        self.tonemap.record(&self.ctx, cmd, src, dst, size, exposure_stops, curve)
    }
}
