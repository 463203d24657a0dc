//! Kernels as types: [`Pipeline<K>`] builds a kernel's compute pipeline from its interface
//! ([`KernelInterface`], generated from `src/gpu/interface.rs`) and records it with the kernel's
//! own resource struct, push-constant type and specialization constants, so a binding is given by
//! name and its number, type and place in the set come from the one definition.

use super::scene::GpuScene;
use crate::error::{Error, Result};
use crate::vk::{raw, ComputePipeline, Context, Descriptor, PipelineDesc, Recorder, Resource, Use};
use std::marker::PhantomData;

pub use super::layout::{
    expand_features, BVH_REGISTERS, BVH_STACK_SPEC_ID, FEATURE_SETS, FIRST_KERNEL_SPEC_ID, SCENE_FEATURES,
    TEXTURE_SLOT_FEATURES,
};

/// A G-buffer as image views: umbra's own ([`crate::passes::gbuffer::GBuffer::views`]) or a host
/// engine's images in the formats and layout [`crate::passes::gbuffer`] documents (`GENERAL`,
/// written before the reading pass with a barrier that makes compute-shader writes visible to
/// compute-shader reads); the kernels bind them as one group (`gbuffer [...]` in `interface/`).
/// umbra never destroys the images behind them.
#[derive(Debug, Clone, Copy)]
pub struct GBufferViews {
    /// Width and height of every image.
    pub size: (u32, u32),
    /// `R32_SFLOAT` view depth.
    pub depth: raw::ImageView,
    /// `R16G16B16A16_SFLOAT` shading normal and roughness.
    pub normal: raw::ImageView,
    /// `R16G16B16A16_SFLOAT` base colour and metallic.
    pub base: raw::ImageView,
    /// `R16G16B16A16_SFLOAT` emission rgb, material occlusion a (1 for none).
    pub emission: raw::ImageView,
    /// `R32G32B32A32_UINT` material index, geometric normal and UV1.
    pub material: raw::ImageView,
    /// `R32G32B32A32_UINT` the layer textures' texels (only for scenes with such textures).
    pub layers: raw::ImageView,
    /// `R32G32B32A32_UINT` more layer textures' texels (only for scenes with a sheen's or a
    /// diffuse transmission's textures).
    pub layers2: raw::ImageView,
    /// `R16G16B16A16_SFLOAT` the surface point's world-space motion since the previous geometry
    /// (only for scenes whose geometry moved: [`crate::gpu::scene::GpuScene::geometry_moved`]).
    pub motion: raw::ImageView,
}

impl GBufferViews {
    /// The views in binding order.
    pub fn in_order(&self) -> [raw::ImageView; 8] {
        [
            self.depth,
            self.normal,
            self.base,
            self.emission,
            self.material,
            self.layers,
            self.layers2,
            self.motion,
        ]
    }
}

/// How a binding is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// `readonly`.
    ReadOnly,
    /// `writeonly` (images only: naga rejects write-only buffers).
    WriteOnly,
    /// Read and written.
    ReadWrite,
    /// Read and written, `coherent`.
    Coherent,
}

/// What a binding is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BindingKind {
    /// A storage buffer holding a runtime array of `arg`.
    Buffer,
    /// A storage buffer holding one `arg` struct.
    BufferStruct,
    /// A 2D storage image of format `arg`.
    Image,
    /// A storage texel buffer of format `arg`.
    Texels,
}

impl BindingKind {
    /// The Vulkan descriptor type.
    pub fn descriptor_type(self) -> raw::DescriptorType {
        match self {
            BindingKind::Buffer | BindingKind::BufferStruct => raw::DescriptorType::STORAGE_BUFFER,
            BindingKind::Image => raw::DescriptorType::STORAGE_IMAGE,
            BindingKind::Texels => raw::DescriptorType::STORAGE_TEXEL_BUFFER,
        }
    }
}

/// One binding of a kernel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BindingDesc {
    /// The name: the variable's for images and texel buffers, the block's one member for buffers.
    pub name: &'static str,
    /// How the kernel reads it.
    pub access: Access,
    /// What it is.
    pub kind: BindingKind,
    /// The element type (buffers) or storage format (images, texel buffers), as in GLSL.
    pub arg: &'static str,
}

/// Which part of the scene's binding block a kernel declares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SceneUse {
    /// None: the kernel's own bindings start at 0.
    None,
    /// The BVH's two bindings (0 and 1).
    Bvh,
    /// The whole block ([`super::layout::SCENE_BINDING_DESCS`]).
    Full,
}

/// One specialization constant of a kernel's own.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SpecDesc {
    /// Its name in Rust (upper case in GLSL).
    pub name: &'static str,
    /// `bool` or `uint`.
    pub ty: &'static str,
}

/// Everything the host and a kernel agree on.
#[derive(Debug)]
pub struct KernelInterface {
    /// The kernel's file stem in `spirv/`.
    pub name: &'static str,
    /// Which part of the scene's bindings it declares.
    pub scene: SceneUse,
    /// The scene features ([`SCENE_FEATURES`]) it is specialised on, as written: features and
    /// names of [`FEATURE_SETS`] ([`KernelInterface::features`] spells them out).
    pub feature_list: &'static [&'static str],
    /// Its own bindings, in order (numbered from [`KernelInterface::first_own_binding`]), as
    /// written: an entry each, a G-buffer group's members in one.
    pub bindings: &'static [&'static [BindingDesc]],
    /// The push-constant struct's name (`()` for none).
    pub push_type: &'static str,
    /// Its size in bytes.
    pub push_size: u32,
    /// Its workgroup size (declared for the GLSL by build.rs).
    pub local: [u32; 3],
    /// Its own specialization constants, ids from [`FIRST_KERNEL_SPEC_ID`] in order.
    pub spec: &'static [SpecDesc],
}

impl KernelInterface {
    /// The binding number of the kernel's first own binding.
    pub fn first_own_binding(&self) -> u32 {
        match self.scene {
            SceneUse::None => 0,
            SceneUse::Bvh | SceneUse::Full => super::layout::SCENE_BINDINGS,
        }
    }

    /// Every binding with its number: the scene's (those the kernel declares), then its own.
    pub fn numbered_bindings(&self) -> Vec<(u32, BindingDesc)> {
        self.bindings_in_order().collect()
    }

    /// [`KernelInterface::numbered_bindings`] without collecting them (each dispatch's bind
    /// reads them).
    pub fn bindings_in_order(&self) -> impl Iterator<Item = (u32, BindingDesc)> + '_ {
        let scene: &[BindingDesc] = match self.scene {
            SceneUse::None => &[],
            SceneUse::Bvh => &super::layout::SCENE_BINDING_DESCS[..2],
            SceneUse::Full => super::layout::SCENE_BINDING_DESCS,
        };
        let first = self.first_own_binding();
        scene.iter().enumerate().map(|(i, b)| (i as u32, *b)).chain(
            self.bindings.iter().flat_map(|e| e.iter()).enumerate().map(move |(i, b)| (first + i as u32, *b)),
        )
    }

    /// The scene features it is specialised on (the others are `false`), each once.
    pub fn features(&self) -> Vec<&'static str> {
        expand_features(self.feature_list)
    }

    /// The constant id of scene feature `name`.
    pub fn feature_id(name: &str) -> Option<u32> {
        SCENE_FEATURES.iter().position(|f| *f == name).map(|i| i as u32)
    }
}

/// What a scene has, for the kernels specialised on it (what it lacks costs nothing).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SceneFeatures {
    /// Some material has a texture.
    pub textures: bool,
    /// Some triangle is alpha-masked or blended.
    pub alpha: bool,
    /// Some triangle emits.
    pub lights: bool,
    /// There are punctual lights.
    pub punctual: bool,
    /// There is an environment map.
    pub env_map: bool,
    /// Some material transmits.
    pub transmission: bool,
    /// Some vertex has a `COLOR_0` other than opaque white.
    pub colors: bool,
    /// Some material is unlit (`KHR_materials_unlit`).
    pub unlit: bool,
    /// Some material has a clear coat (`KHR_materials_clearcoat`).
    pub clearcoat: bool,
    /// Bit k: some material has a texture in slot k (`MATERIAL_SLOT_*`; the features of
    /// [`TEXTURE_SLOT_FEATURES`] cover one slot or a group).
    pub texture_slots: u32,
    /// The BVH holds implicit shapes (`UMBRA_implicit`): the traversal ray-marches them.
    pub implicit: bool,
    /// Some material has parallax occlusion mapping (`UMBRA_implicit`'s `parallax`): shading
    /// marches its height field.
    pub parallax: bool,
    /// Some material has a sheen (`KHR_materials_sheen`).
    pub sheen: bool,
    /// Some material has a thin film (`KHR_materials_iridescence`).
    pub iridescence: bool,
    /// Some material is anisotropic (`KHR_materials_anisotropy`).
    pub anisotropy: bool,
    /// Some material transmits diffusely (`KHR_materials_diffuse_transmission`).
    pub diffuse_transmission: bool,
    /// Some transmitting volume disperses (`KHR_materials_dispersion`).
    pub dispersion: bool,
    /// The entries of the walk's stack in registers: the BVH's stack depth
    /// ([`crate::gpu::bvh::GpuBvhNode::stack_depth`], at least 1) where it is at most
    /// [`BVH_REGISTERS`] (the feature `shallow_bvh`; `BVH_STACK` in `bvh.glsl`), else 0: the
    /// walk keeps its stack in memory. [`GpuBvh::register_stack`](crate::gpu::bvh::GpuBvh::register_stack).
    pub bvh_stack: u32,
}

impl SceneFeatures {
    /// `other`'s features with a walk's stack that also holds these (the deeper of the two,
    /// memory if either is): kernels made for them render both ([`SceneFeatures::renders`];
    /// [`crate::render::Passes::for_moved`]).
    pub fn widened_to(&self, other: &SceneFeatures) -> SceneFeatures {
        let bvh_stack = match (self.bvh_stack, other.bvh_stack) {
            (0, _) | (_, 0) => 0,
            (a, b) => a.max(b),
        };
        SceneFeatures { bvh_stack, ..*other }
    }

    /// The scene's features.
    pub fn of(scene: &GpuScene) -> Self {
        Self {
            textures: scene.texture_count > 0,
            alpha: scene.has_alpha,
            lights: scene.light_count > 0,
            punctual: scene.punctual_count > 0,
            env_map: scene.env_size.is_some(),
            transmission: scene.has_transmission,
            colors: scene.has_colors,
            unlit: scene.has_unlit,
            implicit: scene.has_implicit,
            texture_slots: scene.texture_slots,
            clearcoat: scene.has_clearcoat,
            parallax: scene.has_parallax,
            sheen: scene.has_sheen,
            iridescence: scene.has_iridescence,
            anisotropy: scene.has_anisotropy,
            diffuse_transmission: scene.has_diffuse_transmission,
            dispersion: scene.has_dispersion,
            bvh_stack: scene.bvh.register_stack(),
        }
    }

    /// Whether kernels specialised on these features render a scene with `scene`'s: the same
    /// features, but for a register stack at least as deep as the scene's walk needs or a stack in
    /// memory, which walks any BVH.
    pub fn renders(&self, scene: &SceneFeatures) -> bool {
        let holds = self.bvh_stack == 0 || (scene.bvh_stack != 0 && scene.bvh_stack <= self.bvh_stack);
        holds && SceneFeatures { bvh_stack: 0, ..*self } == SceneFeatures { bvh_stack: 0, ..*scene }
    }

    /// Feature `name` of [`SCENE_FEATURES`].
    pub fn get(&self, name: &str) -> Option<bool> {
        Some(match name {
            "textures" => self.textures,
            "alpha" => self.alpha,
            "lights" => self.lights,
            "punctual" => self.punctual,
            "env_map" => self.env_map,
            "transmission" => self.transmission,
            "colors" => self.colors,
            "unlit" => self.unlit,
            "clearcoat" => self.clearcoat,
            "implicit" => self.implicit,
            "parallax" => self.parallax,
            "sheen" => self.sheen,
            "iridescence" => self.iridescence,
            "anisotropy" => self.anisotropy,
            "diffuse_transmission" => self.diffuse_transmission,
            "dispersion" => self.dispersion,
            "shallow_bvh" => self.bvh_stack != 0,
            _ => {
                let (_, slots) = TEXTURE_SLOT_FEATURES.iter().find(|(f, _)| *f == name)?;
                self.texture_slots & slots != 0
            }
        })
    }
}

/// A specialization constant's value as the 32 bits Vulkan takes.
pub trait SpecValue: Copy {
    /// The value's bits.
    fn to_u32(self) -> u32;
}

impl SpecValue for bool {
    fn to_u32(self) -> u32 {
        self as u32
    }
}

impl SpecValue for u32 {
    fn to_u32(self) -> u32 {
        self
    }
}

/// A kernel's own specialization constants, in id order.
pub trait SpecValues {
    /// Their values.
    fn values(&self) -> Vec<u32>;
}

/// A kernel's resources, in binding order.
pub trait BindResources<'a> {
    /// The descriptors, in binding order.
    fn descriptors(&self) -> Vec<Descriptor<'a>>;
}

/// A kernel of `spirv/` as a type (`crate::gpu::layout::kernels::<name>::Kernel`).
pub trait Kernel {
    /// The resources it binds, by name.
    type Resources<'a>: BindResources<'a>;
    /// Its push constants.
    type Push: bytemuck::Pod;
    /// Its own specialization constants.
    type Spec: SpecValues + Default;
    /// Its workgroup size.
    const LOCAL: [u32; 3];
    /// Its interface.
    const INTERFACE: &'static KernelInterface;
}

/// A compute pipeline of kernel `K`, recorded with `K`'s resources and push constants.
pub struct Pipeline<K: Kernel> {
    pipeline: ComputePipeline,
    _kernel: PhantomData<fn() -> K>,
}

impl<K: Kernel> Pipeline<K> {
    /// The pipeline specialised with `spec` and, for a kernel that depends on them, the scene's
    /// `features` (an error when they are needed and not given).
    pub fn new(ctx: &Context, spec: &K::Spec, features: Option<&SceneFeatures>) -> Result<Self> {
        let clock = std::time::Instant::now();
        let interface = K::INTERFACE;
        let mut specialization = Vec::new();
        let listed = interface.features();
        for &name in &listed {
            let id = KernelInterface::feature_id(name).ok_or_else(|| {
                Error::Invalid(format!("kernel '{}': unknown scene feature '{name}'", interface.name))
            })?;
            let value = features.and_then(|f| f.get(name)).ok_or_else(|| {
                Error::Invalid(format!(
                    "kernel '{}' is specialised on the scene's features: give them",
                    interface.name
                ))
            })?;
            specialization.push((id, value as u32));
        }
        // The register stack's entries, where the kernel walks the BVH with them (any value for
        // a deep BVH, whose walk keeps its stack in memory).
        if listed.contains(&"shallow_bvh") {
            let entries = features.map_or(0, |f| f.bvh_stack);
            specialization.push((BVH_STACK_SPEC_ID, if entries == 0 { BVH_REGISTERS } else { entries }));
        }
        for (i, value) in spec.values().into_iter().enumerate() {
            specialization.push((FIRST_KERNEL_SPEC_ID + i as u32, value));
        }
        let bindings: Vec<(u32, raw::DescriptorType)> =
            interface.bindings_in_order().map(|(n, b)| (n, b.kind.descriptor_type())).collect();
        let pipeline = ComputePipeline::new(
            ctx,
            interface.name,
            &PipelineDesc {
                bindings: &bindings,
                push_constant_size: interface.push_size,
                specialization: &specialization,
            },
        )?;
        log::debug!("pipeline '{}' made in {:.1} ms", interface.name, clock.elapsed().as_secs_f64() * 1e3);
        Ok(Self { pipeline, _kernel: PhantomData })
    }

    /// The pipeline with the default specialization and no scene features.
    pub fn plain(ctx: &Context) -> Result<Self> {
        Self::new(ctx, &K::Spec::default(), None)
    }

    /// The pipeline for `scene`'s features and `spec`.
    pub fn for_scene(ctx: &Context, scene: &GpuScene, spec: &K::Spec) -> Result<Self> {
        Self::new(ctx, spec, Some(&SceneFeatures::of(scene)))
    }

    /// Records one dispatch: binds the pipeline, pushes `resources` and `push`, and dispatches
    /// enough workgroups of the kernel's size ([`Kernel::LOCAL`]) to cover `size` invocations,
    /// after the barrier its bindings' accesses need ([`Recorder`]).
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        resources: &K::Resources<'_>,
        push: &K::Push,
        size: [u32; 3],
    ) -> Result<()> {
        self.bind(rec, resources)?;
        self.push_constants(rec, push)?;
        self.dispatch(rec, size)
    }

    /// Binds the pipeline and pushes `resources` (for several dispatches that differ only in
    /// their push constants: [`Self::push_constants`] and [`Self::dispatch`] after it). Each
    /// binding is read or written as the kernel's interface declares it.
    pub fn bind(&self, rec: &mut Recorder<'_>, resources: &K::Resources<'_>) -> Result<()> {
        let descriptors = resources.descriptors();
        let uses = K::INTERFACE
            .bindings_in_order()
            .zip(&descriptors)
            .map(|((_, binding), descriptor)| {
                let how = match binding.access {
                    Access::ReadOnly => Use::ComputeRead,
                    Access::WriteOnly | Access::ReadWrite | Access::Coherent => Use::ComputeWrite,
                };
                (Resource::of(descriptor), how)
            })
            .collect();
        rec.bind(uses)?;
        self.pipeline.bind(rec.cmd());
        self.pipeline.push_descriptors(rec.cmd(), &descriptors)
    }

    /// Pushes the push constants.
    pub fn push_constants(&self, rec: &mut Recorder<'_>, push: &K::Push) -> Result<()> {
        self.pipeline.push_constants(rec.cmd(), push)
    }

    /// Dispatches the workgroup counts in `buffer` at `offset` (a `VkDispatchIndirectCommand`
    /// that an earlier kernel wrote; `buffer` made with `INDIRECT_BUFFER` usage).
    pub fn dispatch_indirect(&self, rec: &mut Recorder<'_>, buffer: &crate::vk::Buffer, offset: u64) {
        rec.dispatch(Some(buffer.raw));
        self.pipeline.dispatch_indirect(rec.cmd(), buffer.raw, offset)
    }

    /// Dispatches enough workgroups of the kernel's size ([`Kernel::LOCAL`]) to cover `size`
    /// invocations.
    pub fn dispatch(&self, rec: &mut Recorder<'_>, size: [u32; 3]) -> Result<()> {
        rec.dispatch(None);
        self.pipeline.dispatch(rec.cmd(), size, K::LOCAL)
    }
}
