//! The progressive path-tracing pass (`spirv/pathtrace.comp`): one sample per pixel per
//! dispatch into a running mean and second moment.

use crate::bvh::gpu::GpuBvh;
use crate::error::Result;
use crate::gpu::layout::{PathParams, PathStats};
use crate::gpu::scene::GpuScene;
use crate::render::{camera_params, PathSettings};
use crate::scene::Camera;
use crate::vk::{barrier, raw, Buffer, ComputePipeline, Context, Descriptor, MemoryLocation, PipelineDesc};

/// The microfacet distribution of the specular lobes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Microfacet {
    /// GGX with visible-normal sampling (the glTF specification).
    #[default]
    Ggx,
    /// Beckmann with Walter et al.'s half-vector sampling.
    Beckmann,
}

/// How light sampling and BSDF sampling are combined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Heuristic {
    /// Veach's power heuristic (β = 2).
    #[default]
    Power,
    /// The balance heuristic.
    Balance,
}

/// The per-pixel buffers a path-traced image accumulates into.
pub struct PathTarget {
    /// Width and height.
    pub size: (u32, u32),
    /// vec4 per pixel: running mean rgb, sample count.
    pub accum: Buffer,
    /// vec4 per pixel: running mean of the squared samples rgb.
    pub moment: Buffer,
    /// vec4 per pixel: base colour at the first hit (alpha 1 where something was hit).
    pub albedo: Buffer,
    /// vec4 per pixel: shading normal xyz at the first hit, distance in w (inf for a miss).
    pub normal_depth: Buffer,
    /// [`PathStats`].
    pub stats: Buffer,
}

impl PathTarget {
    /// Allocates the buffers (device-local; read back through staging).
    pub fn new(ctx: &Context, (w, h): (u32, u32)) -> Result<Self> {
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER
            | raw::BufferUsageFlags::TRANSFER_SRC
            | raw::BufferUsageFlags::TRANSFER_DST;
        let bytes = w as u64 * h as u64 * 16;
        let make = |name| Buffer::new(ctx, name, bytes, usage, MemoryLocation::GpuOnly);
        Ok(Self {
            size: (w, h),
            accum: make("path accum")?,
            moment: make("path moment")?,
            albedo: make("path albedo")?,
            normal_depth: make("path normal depth")?,
            stats: Buffer::upload(ctx, "path stats", &[PathStats::default()], usage)?,
        })
    }
}

/// `pathtrace.comp`, specialised for one scene's features and the chosen sampling.
pub struct PathTracePass {
    pipeline: ComputePipeline,
}

impl PathTracePass {
    /// Workgroup size of the kernel.
    pub const LOCAL: [u32; 3] = [8, 8, 1];

    /// The pipeline for `scene`: specialised so that what the scene lacks (emissive triangles,
    /// punctual lights, an environment map, textures, transmission, alpha) costs nothing.
    pub fn for_scene(
        ctx: &Context,
        scene: &GpuScene,
        microfacet: Microfacet,
        heuristic: Heuristic,
    ) -> Result<Self> {
        let mut bindings = [raw::DescriptorType::STORAGE_BUFFER; 17];
        bindings[..2].copy_from_slice(&GpuBvh::BINDINGS);
        bindings[16] = raw::DescriptorType::STORAGE_TEXEL_BUFFER;
        let pipeline = ComputePipeline::new(
            ctx,
            "pathtrace",
            &PipelineDesc {
                bindings: &bindings,
                push_constant_size: std::mem::size_of::<PathParams>() as u32,
                specialization: &[
                    (0, (microfacet == Microfacet::Beckmann) as u32),
                    (1, (heuristic == Heuristic::Power) as u32),
                    (2, (scene.light_count > 0) as u32),
                    (3, (scene.punctual_count > 0) as u32),
                    (4, scene.env_size.is_some() as u32),
                    (5, (scene.texture_count > 0) as u32),
                    (6, scene.has_transmission as u32),
                    (7, scene.has_alpha as u32),
                ],
            },
        )?;
        Ok(Self { pipeline })
    }

    /// The push constants for sample 0 of `settings` seen from `camera` (`size_frame[2]` is the
    /// sample index: set it per dispatch).
    pub fn params(scene: &GpuScene, camera: &Camera, settings: &PathSettings) -> PathParams {
        let (cam_origin, cam_forward, cam_right, cam_up) = camera_params(camera, settings.size);
        let (env_w, env_h) = scene.env_size.unwrap_or((1, 1));
        PathParams {
            cam_origin,
            cam_forward,
            cam_right,
            cam_up,
            env: [settings.env[0], settings.env[1], settings.env[2], 0.0],
            size_frame: [settings.size.0, settings.size.1, 0, settings.seed],
            settings: [settings.max_bounces, settings.rr_depth, scene.light_count, scene.punctual_count],
            env_info: [env_w, env_h, settings.env_nee as u32, 0],
        }
    }

    /// Records one sample per pixel (sample `params.size_frame[2]`), then a barrier so the next
    /// dispatch or a copy sees it. Never submits.
    pub fn record(
        &self,
        ctx: &Context,
        cmd: raw::CommandBuffer,
        scene: &GpuScene,
        target: &PathTarget,
        params: &PathParams,
    ) -> Result<()> {
        self.pipeline.record(
            cmd,
            &[
                scene.bvh.descriptors()[0],
                scene.bvh.descriptors()[1],
                Descriptor::Buffer(&scene.triangles),
                Descriptor::Buffer(&scene.vertices),
                Descriptor::Buffer(&scene.materials),
                Descriptor::Buffer(&scene.lights),
                Descriptor::Buffer(&target.accum),
                Descriptor::Buffer(&target.moment),
                Descriptor::Buffer(&target.albedo),
                Descriptor::Buffer(&target.normal_depth),
                Descriptor::Buffer(&target.stats),
                Descriptor::Buffer(&scene.punctual),
                Descriptor::Buffer(&scene.env_texels),
                Descriptor::Buffer(&scene.env_marginal),
                Descriptor::Buffer(&scene.env_conditional),
                Descriptor::Buffer(&scene.textures),
                Descriptor::Texels(&scene.texels),
            ],
            params,
            [target.size.0, target.size.1, 1],
            Self::LOCAL,
        )?;
        barrier::compute_to_compute(ctx, cmd);
        Ok(())
    }
}

/// `resolve.comp`: a [`PathTarget`]'s running mean into an `R32G32B32A32_SFLOAT` storage image.
pub struct ResolvePass {
    pipeline: ComputePipeline,
}

impl ResolvePass {
    /// Builds the pipeline.
    pub fn new(ctx: &Context) -> Result<Self> {
        let pipeline = ComputePipeline::new(
            ctx,
            "resolve",
            &PipelineDesc {
                bindings: &[raw::DescriptorType::STORAGE_BUFFER, raw::DescriptorType::STORAGE_IMAGE],
                push_constant_size: 16,
                specialization: &[],
            },
        )?;
        Ok(Self { pipeline })
    }

    /// Records the copy of `target`'s mean into `output` (a storage image of the target's size
    /// in `GENERAL` layout) and a compute-to-compute barrier after it. Never submits.
    pub fn record(
        &self,
        ctx: &Context,
        cmd: raw::CommandBuffer,
        target: &PathTarget,
        output: raw::ImageView,
    ) -> Result<()> {
        self.pipeline.record(
            cmd,
            &[Descriptor::Buffer(&target.accum), Descriptor::StorageView(output)],
            &[target.size.0, target.size.1, 0, 0],
            [target.size.0, target.size.1, 1],
            [8, 8, 1],
        )?;
        barrier::compute_to_compute(ctx, cmd);
        Ok(())
    }
}
