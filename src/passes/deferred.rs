//! Deferred lighting (`spirv/deferred.comp`): the G-buffer shaded with the path tracer's BSDF
//! (`shading.glsl`, `bsdf.glsl`): emission, punctual lights and emissive triangles with
//! ray-traced shadows, into a linear `R32G32B32A32_SFLOAT` image (`GENERAL` layout; alpha 1).
//! Pixels without a surface get the environment seen directly. Split-sum image-based lighting
//! ([`IblResources`], precomputed once per scene) times an ambient-occlusion image lights every
//! surface with the environment (a constant or the scene's map). Transmissive materials transmit
//! the prefiltered environment through their one interface (straight on when thin-walled,
//! refracted once into a volume); the G-buffer holds only the first surface, so a volume's exit
//! and anything behind a transmissive surface but the environment are not seen.

use super::gbuffer::GBufferViews;
use super::ibl::IblResources;
use crate::bvh::gpu::GpuBvh;
use crate::error::{Error, Result};
use crate::gpu::layout::DeferredParams;
use crate::gpu::scene::GpuScene;
use crate::render::camera_params;
use crate::scene::Camera;
use crate::vk::{barrier, raw, ComputePipeline, Context, Descriptor, Image, PipelineDesc};

/// What the lighting pass computes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightingSettings {
    /// Shadow rays (light samples) per pixel for the emissive triangles; soft shadows converge as
    /// this grows (punctual lights always take one).
    pub shadow_rays: u32,
    /// Frame index, decorrelating the light samples of successive frames.
    pub frame: u32,
    /// Seed of the light samples.
    pub seed: u32,
    /// Constant environment radiance, or the environment map's multiplier (rgb).
    pub env: [f32; 3],
    /// Split-sum image-based lighting of the environment (times ambient occlusion).
    pub ibl: bool,
    /// Which direction the prefiltered environment is read along.
    pub ibl_lookup: IblLookup,
}

impl Default for LightingSettings {
    fn default() -> Self {
        Self { shadow_rays: 4, frame: 0, seed: 0, env: [0.0; 3], ibl: true, ibl_lookup: IblLookup::Dominant }
    }
}

impl LightingSettings {
    /// Most shadow rays per pixel: one invocation traces them all, and CPU devices (llvmpipe)
    /// break every loop of an invocation after 65,535 loop iterations in all; 64 rays through a
    /// Sponza-class BVH stay well inside it.
    pub const MAX_SHADOW_RAYS: u32 = 64;

    /// Checks the settings: 1 to [`Self::MAX_SHADOW_RAYS`] shadow rays, a finite non-negative
    /// environment.
    pub fn validate(&self) -> Result<()> {
        if self.shadow_rays == 0 || self.shadow_rays > Self::MAX_SHADOW_RAYS {
            return Err(Error::Invalid(format!(
                "{} shadow rays per pixel: must be 1 to {} (one kernel invocation traces them all, and CPU \
                 devices cut loops short past 65,535 iterations)",
                self.shadow_rays,
                Self::MAX_SHADOW_RAYS
            )));
        }
        if !self.env.iter().all(|c| c.is_finite() && *c >= 0.0) {
            return Err(Error::Invalid(format!(
                "environment radiance {:?} must be finite and non-negative",
                self.env
            )));
        }
        Ok(())
    }
}

/// The direction along which the split sum reads its prefiltered environment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum IblLookup {
    /// The mirror direction: the prefiltering's own n = v = r assumption (the textbook split sum).
    Mirror,
    /// The lobe's dominant direction, leaning from the mirror direction towards the normal as
    /// roughness grows (Lagarde and de Rousiers 2014): much closer for rough surfaces.
    #[default]
    Dominant,
}

/// `deferred.comp`, specialised for the scene's features.
pub struct DeferredPass {
    pipeline: ComputePipeline,
    /// 1×1 `R32_SFLOAT` of 1.0: the ambient occlusion when the caller has none.
    no_ao: Image,
}

impl DeferredPass {
    /// Workgroup size of the kernel.
    pub const LOCAL: [u32; 3] = [8, 8, 1];

    /// Builds the pipeline for what `scene` has (textures, emissive triangles, punctual lights,
    /// an environment map).
    pub fn new(ctx: &Context, scene: &GpuScene) -> Result<Self> {
        let mut bindings = [raw::DescriptorType::STORAGE_BUFFER; 22];
        bindings[12..18].fill(raw::DescriptorType::STORAGE_IMAGE);
        bindings[21] = raw::DescriptorType::STORAGE_IMAGE;
        bindings[..2].copy_from_slice(&GpuBvh::BINDINGS);
        bindings[8] = raw::DescriptorType::STORAGE_TEXEL_BUFFER;
        let pipeline = ComputePipeline::new(
            ctx,
            "deferred",
            &PipelineDesc {
                bindings: &bindings,
                push_constant_size: std::mem::size_of::<DeferredParams>() as u32,
                specialization: &[
                    (0, (scene.texture_count > 0) as u32),
                    (1, (scene.light_count > 0) as u32),
                    (2, (scene.punctual_count > 0) as u32),
                    (3, scene.env_size.is_some() as u32),
                    (4, 0),
                    (5, scene.has_alpha as u32),
                    (6, scene.has_transmission as u32),
                ],
            },
        )?;
        let no_ao = Image::storage_2d(ctx, "no ambient occlusion", 1, 1, raw::Format::R32_SFLOAT)?;
        no_ao.write(ctx, &[1.0f32])?;
        Ok(Self { pipeline, no_ao })
    }

    /// The push constants for `camera` over an image of `size`.
    pub fn params(
        scene: &GpuScene,
        camera: &Camera,
        size: (u32, u32),
        settings: &LightingSettings,
    ) -> DeferredParams {
        let (cam_origin, cam_forward, cam_right, cam_up) = camera_params(camera, size);
        let (env_w, env_h) = scene.env_size.unwrap_or((1, 1));
        let [r, g, b] = settings.env;
        DeferredParams {
            cam_origin,
            cam_forward,
            cam_right,
            cam_up,
            env: [r, g, b, 0.0],
            size_frame: [size.0, size.1, settings.frame, settings.seed],
            counts: [
                scene.light_count,
                scene.punctual_count,
                settings.shadow_rays.max(1),
                settings.ibl as u32 | ((settings.ibl_lookup == IblLookup::Dominant) as u32) << 1,
            ],
            env_info: [env_w, env_h, 0, 0],
        }
    }

    /// Records the pass (G-buffer in, `output` written: an `R32G32B32A32_SFLOAT` storage image in
    /// `GENERAL` layout of the G-buffer's size) and a compute-to-compute barrier after it. Never
    /// submits. `ibl` holds the scene's precomputed tables (recorded before this pass); `ao` is an
    /// `R32_SFLOAT` image of the G-buffer's size in `GENERAL` layout (1 = unoccluded), or none.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        ctx: &Context,
        cmd: raw::CommandBuffer,
        scene: &GpuScene,
        gbuffer: &GBufferViews,
        output: raw::ImageView,
        ibl: &IblResources,
        ao: Option<raw::ImageView>,
        params: &DeferredParams,
    ) -> Result<()> {
        let mut resources = vec![
            scene.bvh.descriptors()[0],
            scene.bvh.descriptors()[1],
            Descriptor::Buffer(&scene.triangles),
            Descriptor::Buffer(&scene.vertices),
            Descriptor::Buffer(&scene.materials),
            Descriptor::Buffer(&scene.lights),
            Descriptor::Buffer(&scene.punctual),
            Descriptor::Buffer(&scene.textures),
            Descriptor::Texels(&scene.texels),
            Descriptor::Buffer(&scene.env_texels),
            Descriptor::Buffer(&scene.env_marginal),
            Descriptor::Buffer(&scene.env_conditional),
        ];
        resources.extend(gbuffer.in_order().map(Descriptor::StorageView));
        resources.push(Descriptor::StorageView(output));
        resources.push(Descriptor::Buffer(&ibl.lut));
        resources.push(Descriptor::Buffer(&ibl.prefiltered));
        resources.push(Descriptor::Buffer(&ibl.sh));
        resources.push(Descriptor::StorageView(ao.unwrap_or(self.no_ao.view)));
        self.pipeline.record(cmd, &resources, params, [gbuffer.size.0, gbuffer.size.1, 1], Self::LOCAL)?;
        barrier::compute_to_compute(ctx, cmd);
        Ok(())
    }
}
