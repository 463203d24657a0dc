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
//! renderer.record_lighting(cmd, &camera, &gbuffer_views, hdr_view, &lighting)?;
//! renderer.record_tonemap(cmd, hdr_view, ldr_view, size, 0.0, ToneCurve::KhronosPbrNeutral)?;
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

use crate::error::Result;
use crate::gpu::scene::GpuScene;
use crate::passes::deferred::{DeferredPass, LightingSettings};
use crate::passes::gbuffer::{GBufferPass, GBufferViews};
use crate::passes::ibl::{IblResources, IblSettings};
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
    tonemap: TonemapPass,
}

impl Renderer {
    /// Builds the BVH, uploads the scene and creates the pipelines it needs.
    pub fn new(ctx: &Context, scene: &Scene) -> Result<Self> {
        let gpu_scene = GpuScene::upload(ctx, scene)?;
        Ok(Self {
            gbuffer: GBufferPass::new(ctx, gpu_scene.texture_count > 0)?,
            deferred: DeferredPass::new(ctx, &gpu_scene)?,
            ibl: IblResources::build(ctx, &gpu_scene, &IblSettings::default())?,
            tonemap: TonemapPass::new(ctx)?,
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
        self.gbuffer = GBufferPass::new(&self.ctx, self.scene.texture_count > 0)?;
        self.deferred = DeferredPass::new(&self.ctx, &self.scene)?;
        Ok(())
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

    /// Records deferred lighting of `gbuffer` (umbra's or the host's own) seen from `camera` into
    /// `output` (`R32G32B32A32_SFLOAT`, the G-buffer's size).
    pub fn record_lighting(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        gbuffer: &GBufferViews,
        output: raw::ImageView,
        settings: &LightingSettings,
    ) -> Result<()> {
        let params = DeferredPass::params(&self.scene, camera, gbuffer.size, settings);
        self.deferred.record(&self.ctx, cmd, &self.scene, gbuffer, output, &self.ibl, None, &params)
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
