//! The G-buffer pass (`spirv/gbuffer.comp`): one primary ray through each pixel's centre, and the
//! first surface's attributes in storage images, for the deferred passes (SSAO, lighting).
//!
//! | image | format | contents |
//! |---|---|---|
//! | `depth` | `R32_SFLOAT` | view-space depth (distance along the camera's forward axis); 0 where no surface |
//! | `normal` | `R16G16B16A16_SFLOAT` | world-space shading normal xyz (interpolated, normal-mapped, facing the camera's side of the geometry), perceptual roughness √α in w (α floored as the BSDF floors it) |
//! | `base` | `R16G16B16A16_SFLOAT` | linear base colour rgb (textures applied, mipmapped ones filtered for the pixel's ray cone), metallic in a |
//! | `emission` | `R16G16B16A16_SFLOAT` | emitted radiance towards the camera rgb (clamped to 65504); the material's ambient occlusion in a (glTF `occlusionTexture`: 1 + strength (r − 1), filtered like the other textures; 1 without one), which the lighting pass multiplies into the image-based (ambient) light only |
//! | `material` | `R32G32B32A32_UINT` | x: material index ([`GBUFFER_NO_SURFACE`] where none); y: geometric normal facing the camera, octahedral, `packSnorm2x16`; z, w: the `TEXCOORD_1` coordinates as float bits (0 without them), where lightmaps are looked up |
//! | `layers` | `R32G32B32A32_UINT` | the texels of the material's layer textures (filtered like the other textures; 1 where a slot is empty), four `packUnorm4x8` values a word (exact for 8-bit linear texels read unfiltered, within 1/510 otherwise): x: `specularColorTexture` rgb, `specularTexture` a; y: `transmissionTexture` r, `clearcoatTexture` r, `clearcoatRoughnessTexture` g, `KHR_materials_volume`'s `thicknessTexture` g; z: the clear coat's normal (octahedral, two snorm16); w: `iridescenceTexture` r and `iridescenceThicknessTexture` g (two `packUnorm2x16` values). Written (and read by the lighting passes) only where the scene has some such texture: a host may leave it unwritten for scenes without |
//! | `layers2` | `R32G32B32A32_UINT` | more layer textures' texels, as `layers`: x: `KHR_materials_sheen`'s `sheenColorTexture` rgb, `sheenRoughnessTexture` a; y: `KHR_materials_diffuse_transmission`'s `diffuseTransmissionColorTexture` rgb, `diffuseTransmissionTexture` a; z, w: unused (0). Written (and read) only where the scene has such a texture |
//!
//! | `motion` | `R16G16B16A16_SFLOAT` | the surface point's world-space motion xyz since the scene's previous geometry (its vertices' motion at the point's barycentrics; [`GpuScene::geometry_moved`]), which temporal anti-aliasing moves the point back by; w 0. Written (and read) only for a scene whose geometry moved: a host may leave it unwritten for still geometry |
//!
//! Every image is in `GENERAL` layout, written by compute shader storage writes. Where no surface was hit, `depth`, `normal`, `base` and
//! `emission` (its a included) are 0.
//!
//! A host that writes its own G-buffer must write the occlusion too: 1 in `emission`'s a where a
//! surface has no occlusion map (0 there darkens the image-based light to nothing).

use crate::error::{Error, Result};
pub use crate::gpu::kernel::GBufferViews;
use crate::gpu::kernels::gbuffer;
pub use crate::gpu::layout::GBUFFER_NO_SURFACE;
use crate::gpu::layout::{GBufferParams, GpuCamera};
use crate::gpu::scene::GpuScene;
use crate::gpu::{Pipeline, SceneFeatures};
pub use crate::passes::visibility::{GBufferMethod, VisibilityBuffer};
use crate::scene::Camera;
use crate::vk::{raw, Buffer, Context, Graph, GraphImage, GraphViews, Image, Recorder};
use gpu_allocator::MemoryLocation;

/// The G-buffer images (see the module documentation for their formats and contents).
pub struct GBuffer {
    /// Width and height.
    pub size: (u32, u32),
    /// View-space depth.
    pub depth: Image,
    /// Shading normal and roughness.
    pub normal: Image,
    /// Base colour and metallic.
    pub base: Image,
    /// Emitted radiance and the material's occlusion.
    pub emission: Image,
    /// Material index and geometric normal.
    pub material: Image,
    /// The layer textures' texels.
    pub layers: Image,
    /// More layer textures' texels (the sheen's, the diffuse transmission's).
    pub layers2: Image,
    /// The surface point's motion since the previous geometry.
    pub motion: Image,
}

impl GBuffer {
    /// Allocates the images and moves them to `GENERAL` layout.
    pub fn new(ctx: &Context, (w, h): (u32, u32)) -> Result<Self> {
        let make = |name, format| Image::storage_2d(ctx, name, w, h, format);
        let gbuffer = Self {
            size: (w, h),
            depth: make("gbuffer depth", raw::Format::R32_SFLOAT)?,
            normal: make("gbuffer normal", raw::Format::R16G16B16A16_SFLOAT)?,
            base: make("gbuffer base", raw::Format::R16G16B16A16_SFLOAT)?,
            emission: make("gbuffer emission", raw::Format::R16G16B16A16_SFLOAT)?,
            material: make("gbuffer material", raw::Format::R32G32B32A32_UINT)?,
            layers: make("gbuffer layers", raw::Format::R32G32B32A32_UINT)?,
            layers2: make("gbuffer layers2", raw::Format::R32G32B32A32_UINT)?,
            motion: make("gbuffer motion", raw::Format::R16G16B16A16_SFLOAT)?,
        };
        ctx.submit(|cmd| {
            for image in gbuffer.images() {
                image.init_general(ctx, cmd);
            }
            Ok(())
        })?;
        Ok(gbuffer)
    }

    /// The images in binding order.
    pub fn images(&self) -> [&Image; 8] {
        [
            &self.depth,
            &self.normal,
            &self.base,
            &self.emission,
            &self.material,
            &self.layers,
            &self.layers2,
            &self.motion,
        ]
    }

    /// Views of the images, for the passes that read a G-buffer.
    pub fn views(&self) -> GBufferViews {
        GBufferViews {
            size: self.size,
            depth: self.depth.view,
            normal: self.normal.view,
            base: self.base.view,
            emission: self.emission.view,
            material: self.material.view,
            layers: self.layers.view,
            layers2: self.layers2.view,
            motion: self.motion.view,
        }
    }

    /// Reads every image back (waits for the GPU).
    pub fn read(&self, ctx: &Context) -> Result<GBufferData> {
        let half = |image: &Image| -> Result<Vec<[f32; 4]>> {
            let texels: Vec<[u16; 4]> = image.read(ctx)?;
            Ok(texels.iter().map(|t| t.map(|h| half::f16::from_bits(h).to_f32())).collect())
        };
        Ok(GBufferData {
            size: self.size,
            depth: self.depth.read(ctx)?,
            normal: half(&self.normal)?,
            base: half(&self.base)?,
            emission: half(&self.emission)?,
            material: self.material.read(ctx)?,
            layers: self.layers.read(ctx)?,
            layers2: self.layers2.read(ctx)?,
        })
    }
}

/// A G-buffer's images in a frame graph ([`crate::vk::Graph`]), in binding order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GBufferImages {
    /// Width and height of every image.
    pub size: (u32, u32),
    /// The images in [`GBufferViews::in_order`]'s order.
    pub images: [GraphImage; 8],
}

impl GBufferImages {
    /// The views of the images while `graph` records.
    pub fn views(&self, views: &GraphViews) -> GBufferViews {
        let [depth, normal, base, emission, material, layers, layers2, motion] =
            self.images.map(|i| views[i]);
        GBufferViews { size: self.size, depth, normal, base, emission, material, layers, layers2, motion }
    }

    /// Imports the caller's G-buffer `views` into `graph`.
    pub fn import(graph: &mut Graph<'_>, views: &GBufferViews) -> Self {
        const NAMES: [&str; 8] = [
            "gbuffer depth",
            "gbuffer normal",
            "gbuffer base",
            "gbuffer emission",
            "gbuffer material",
            "gbuffer layers",
            "gbuffer layers2",
            "gbuffer motion",
        ];
        let in_order = views.in_order();
        Self { size: views.size, images: std::array::from_fn(|i| graph.import(NAMES[i], in_order[i])) }
    }
}

/// A G-buffer on the host, row-major from the top left (the AOVs of a hybrid render).
#[derive(Debug, Clone)]
pub struct GBufferData {
    /// Width and height.
    pub size: (u32, u32),
    /// View-space depth; 0 where no surface.
    pub depth: Vec<f32>,
    /// Shading normal xyz, roughness.
    pub normal: Vec<[f32; 4]>,
    /// Base colour rgb, metallic.
    pub base: Vec<[f32; 4]>,
    /// Emitted radiance rgb, the material's occlusion (1 for none; 0 where no surface).
    pub emission: Vec<[f32; 4]>,
    /// Material index, packed geometric normal.
    pub material: Vec<[u32; 4]>,
    /// The layer textures' texels, unorm8 × 4 a word (unwritten for a scene without them).
    pub layers: Vec<[u32; 4]>,
    /// More layer textures' texels, as `layers` (unwritten for a scene without them).
    pub layers2: Vec<[u32; 4]>,
}

/// `gbuffer.comp`, specialised for whether the scene has textures and alpha-tested materials,
/// and for ray casting or resolving a visibility buffer.
pub struct GBufferPass {
    pipeline: Pipeline<gbuffer::Kernel>,
    raster: bool,
    /// The `visibility` binding of the ray-cast kernel, which never reads it.
    no_visibility: Buffer,
}

impl GBufferPass {
    /// Builds the ray-cast pipeline for what `scene` has (textures, alpha-tested materials).
    pub fn new(ctx: &Context, scene: &GpuScene) -> Result<Self> {
        Self::for_features(ctx, &scene.features())
    }

    /// [`GBufferPass::new`] for a scene with `features` (before it is uploaded).
    pub fn for_features(ctx: &Context, features: &SceneFeatures) -> Result<Self> {
        Self::with_raster(ctx, features, false)
    }

    /// The pipeline that ray-casts (`raster` false) or resolves a [`VisibilityBuffer`]
    /// (`raster` true), for a scene with `features`.
    pub fn with_raster(ctx: &Context, features: &SceneFeatures, raster: bool) -> Result<Self> {
        let storage = raw::BufferUsageFlags::STORAGE_BUFFER;
        Ok(Self {
            pipeline: Pipeline::new(ctx, &gbuffer::Spec { raster }, Some(features))?,
            raster,
            no_visibility: Buffer::new(ctx, "no visibility buffer", 8, storage, MemoryLocation::GpuOnly)?,
        })
    }

    /// The push constants for `camera` over an image of `size`.
    pub fn params(camera: &Camera, size: (u32, u32)) -> GBufferParams {
        GBufferParams { camera: GpuCamera::new(camera, size), size: [size.0, size.1], ..Default::default() }
    }

    /// Records the pass into `target` (umbra's [`GBuffer::views`] or a host's images in the same
    /// formats, `GENERAL` layout), resolving `visibility` (recorded before, for this camera and
    /// size) where the pipeline was made to. Never submits.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        target: &GBufferViews,
        params: &GBufferParams,
        visibility: Option<&VisibilityBuffer>,
    ) -> Result<()> {
        let mut params = *params;
        let buffer = match (self.raster, visibility) {
            (false, None) => &self.no_visibility,
            (true, Some(vis)) if vis.size() == target.size => {
                params.vis_stride = vis.stride();
                &vis.visibility
            }
            (true, Some(vis)) => {
                return Err(Error::Invalid(format!(
                    "a visibility buffer of {:?} for a G-buffer of {:?}",
                    vis.size(),
                    target.size
                )))
            }
            (true, None) => {
                return Err(Error::Invalid("the raster G-buffer needs a visibility buffer".into()))
            }
            (false, Some(_)) => {
                return Err(Error::Invalid("the ray-cast G-buffer pass was given a visibility buffer".into()))
            }
        };
        params.motion = scene.geometry_moved() as u32;
        let resources = gbuffer::Resources {
            scene,
            gb: target,
            visibility: buffer,
            vertex_motion: scene.vertex_motion(),
        };
        self.pipeline.record(rec, &resources, &params, [target.size.0, target.size.1, 1])?;
        Ok(())
    }
}
