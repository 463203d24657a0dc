//! Everything Rust and the kernels share, generated from one definition,
//! `src/gpu/interface.rs`: the `#[repr(C)]` structs (each with a GLSL twin of the same name and
//! members in the generated `layout.glsl`), the constants both sides read, the scene's binding
//! block and, in [`kernels`], one module per kernel with its typed resources, push constants and
//! specialization constants. `build.rs` reads the same file to write the GLSL declarations, and
//! `tests/layout.rs` checks every compiled kernel against [`gpu_layouts`] and
//! [`kernels::all`] through naga, so neither side can drift.

use super::kernel::{Access, BindingDesc, BindingKind, SpecDesc};
use bytemuck::{Pod, Zeroable};
use std::mem::{offset_of, size_of};

/// The Rust type of a GLSL type name in `interface.rs`.
macro_rules! rust_ty {
    (bool) => {
        bool
    };
    (float) => {
        f32
    };
    (uint) => {
        u32
    };
    (int) => {
        i32
    };
    (vec2) => {
        [f32; 2]
    };
    (vec3) => {
        [f32; 3]
    };
    (vec4) => {
        [f32; 4]
    };
    (uvec2) => {
        [u32; 2]
    };
    (uvec3) => {
        [u32; 3]
    };
    (uvec4) => {
        [u32; 4]
    };
    (ivec2) => {
        [i32; 2]
    };
    ([$t:tt; $n:literal]) => {
        [rust_ty!($t); $n]
    };
    ($t:ident) => {
        $t
    };
}

/// A field's Rust type: its GLSL type's, or the `as` override.
macro_rules! field_ty {
    ($t:tt as $rust:ty) => {
        $rust
    };
    ($t:tt) => {
        rust_ty!($t)
    };
}

/// An item as its role in `interface.rs` has it: `struct` and `kernel` always, `test_struct`
/// and `test_kernel` with the `testing` feature only (and hidden from the docs).
macro_rules! gated {
    (struct, $($item:item)*) => { $($item)* };
    (kernel, $($item:item)*) => { $($item)* };
    (texel_struct, $($item:item)*) => { $($item)* };
    (test_struct, $($item:item)*) => { $(#[cfg(feature = "testing")] #[doc(hidden)] $item)* };
    (test_kernel, $($item:item)*) => { $(#[cfg(feature = "testing")] #[doc(hidden)] $item)* };
}

/// A statement as its role has it (see [`gated`]).
macro_rules! gated_statement {
    (struct, $s:stmt) => {
        $s
    };
    (kernel, $s:stmt) => {
        $s
    };
    (texel_struct, $s:stmt) => {
        $s
    };
    (test_struct, $s:stmt) => {
        #[cfg(feature = "testing")]
        $s
    };
    (test_kernel, $s:stmt) => {
        #[cfg(feature = "testing")]
        $s
    };
}

macro_rules! gpu_structs {
    ($group:ident; $($(#[$meta:meta])* $role:ident $name:ident {
        $($(#[$fmeta:meta])* $field:ident : $ty:tt $(as $rust:ty)?),* $(,)?
    })*) => {
        $(
            gated!($role,
                $(#[$meta])*
                #[repr(C)]
                #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
                pub struct $name {
                    $($(#[$fmeta])* pub $field: field_ty!($ty $(as $rust)?),)*
                }
            );
        )*

        $(texel_struct_items!($role, $name);)*

        mod $group {
            use super::*;

            /// The group's structs' layouts, in order.
            #[allow(clippy::vec_init_then_push)] // some pushes are cfg'd out
            pub(super) fn layouts() -> Vec<StructLayout> {
                let mut layouts = Vec::new();
                $(gated_statement!($role, layouts.push({
                    let zero = <$name as Zeroable>::zeroed();
                    StructLayout {
                        name: stringify!($name),
                        size: size_of::<$name>(),
                        members: vec![$(MemberLayout {
                            name: stringify!($field),
                            offset: offset_of!($name, $field),
                            size: std::mem::size_of_val(&zero.$field),
                        }),*],
                    }
                }));)*
                layouts
            }
        }
    };
}

/// A `texel_struct`'s own items: its texel count (build.rs gives the kernels the same count and
/// each member's first texel, from the same member list).
macro_rules! texel_struct_items {
    (texel_struct, $name:ident) => {
        impl $name {
            /// Texels (16 bytes each) of one value in a texel buffer (the kernels' constant
            /// of the same meaning, e.g. `MATERIAL_TEXELS`).
            pub const TEXELS: u32 = (size_of::<$name>() / 16) as u32;
        }
        const _: () = assert!(size_of::<$name>() % 16 == 0);
    };
    ($role:ident, $name:ident) => {};
}

/// The groups of structs `interface.rs` includes, in order.
macro_rules! struct_groups {
    ($($group:ident),* $(,)?) => {
        /// Every host/GPU struct pair: each member's name, offset and size, and the struct's
        /// size (which is also its array stride).
        pub fn gpu_layouts() -> Vec<StructLayout> {
            let mut layouts = Vec::new();
            $(layouts.extend($group::layouts());)*
            layouts
        }
    };
}

macro_rules! gpu_constants {
    ($($(#[$meta:meta])* $name:ident : $ty:tt = $value:expr;)*) => {
        $($(#[$meta])* pub const $name: rust_ty!($ty) = $value;)*
    };
}

/// The bindings of one entry of a kernel's bindings: a G-buffer group's members, or the one.
macro_rules! binding_descs {
    ($name:ident, $access:ident gbuffer [$($member:ident),* $(,)?]) => {
        &[$(BindingDesc {
            name: concat!(stringify!($name), "_", stringify!($member)),
            access: access!($access),
            kind: BindingKind::Image,
            arg: gbuffer_format!($member),
        }),*]
    };
    ($name:ident, $access:ident $kind:ident $arg:tt) => {
        &[binding_desc!($name, $access $kind $arg)]
    };
}

/// The binding kind of `access kind arg`.
macro_rules! binding_desc {
    ($name:ident, $access:ident buffer [$elem:tt]) => {
        BindingDesc {
            name: stringify!($name),
            access: access!($access),
            kind: BindingKind::Buffer,
            arg: stringify!($elem),
        }
    };
    ($name:ident, $access:ident buffer $elem:tt) => {
        BindingDesc {
            name: stringify!($name),
            access: access!($access),
            kind: BindingKind::BufferStruct,
            arg: stringify!($elem),
        }
    };
    ($name:ident, $access:ident image $format:tt) => {
        BindingDesc {
            name: stringify!($name),
            access: access!($access),
            kind: BindingKind::Image,
            arg: stringify!($format),
        }
    };
    ($name:ident, $access:ident texels $format:tt) => {
        BindingDesc {
            name: stringify!($name),
            access: access!($access),
            kind: BindingKind::Texels,
            arg: stringify!($format),
        }
    };
}

macro_rules! access {
    (readonly) => {
        Access::ReadOnly
    };
    (writeonly) => {
        Access::WriteOnly
    };
    (readwrite) => {
        Access::ReadWrite
    };
    (coherent) => {
        Access::Coherent
    };
}

/// The Rust resource a binding takes: a buffer, an image view, a texel buffer.
macro_rules! resource_ty {
    ($lt:lifetime buffer) => { &$lt crate::vk::Buffer };
    ($lt:lifetime image) => { &$lt crate::vk::raw::ImageView };
    ($lt:lifetime texels) => { &$lt crate::vk::TexelBuffer };
    ($lt:lifetime gbuffer) => { &$lt crate::gpu::kernel::GBufferViews };
}

/// The descriptors of one entry of a kernel's bindings (a G-buffer group's members, or the one).
macro_rules! descriptors {
    (gbuffer [$($member:ident),* $(,)?], $v:expr) => {
        [$(crate::vk::Descriptor::StorageView($v.$member)),*]
    };
    ($kind:ident $arg:tt, $v:expr) => {
        [descriptor!($kind, $v)]
    };
}

macro_rules! descriptor {
    (buffer, $v:expr) => {
        crate::vk::Descriptor::Buffer($v)
    };
    (image, $v:expr) => {
        crate::vk::Descriptor::StorageView(*$v)
    };
    (texels, $v:expr) => {
        crate::vk::Descriptor::Texels($v)
    };
}

macro_rules! scene_bindings {
    ($($(#[$meta:meta])* $name:ident : $access:ident $kind:ident $arg:tt),* $(,)?) => {
        /// The scene's bindings, numbered from 0 in every kernel that reads the scene.
        pub static SCENE_BINDING_DESCS: &[BindingDesc] = &[$(binding_desc!($name, $access $kind $arg)),*];

        /// The first binding number after the scene's block: a kernel's own bindings start here.
        pub const SCENE_BINDINGS: u32 = SCENE_BINDING_DESCS.len() as u32;

        /// The scene's resources, one field per binding of the scene block, by name.
        pub struct SceneResources<'a> {
            $($(#[$meta])* pub $name: resource_ty!('a $kind),)*
        }

        impl<'a> SceneResources<'a> {
            /// The descriptors in binding order.
            pub fn descriptors(&self) -> Vec<crate::vk::Descriptor<'a>> {
                vec![$(descriptor!($kind, self.$name)),*]
            }
        }
    };
}

/// A kernel's resources: the scene (or its BVH) and its own bindings by name.
macro_rules! resources_struct {
    (full; $($(#[$bmeta:meta])* $name:ident : $kind:ident),*) => {
        /// The resources the kernel binds, by name.
        pub struct Resources<'a> {
            /// The scene (its binding block).
            pub scene: &'a crate::gpu::scene::GpuScene,
            $($(#[$bmeta])* pub $name: resource_ty!('a $kind),)*
        }
    };
    (bvh; $($(#[$bmeta:meta])* $name:ident : $kind:ident),*) => {
        /// The resources the kernel binds, by name.
        pub struct Resources<'a> {
            /// The BVH (the first two bindings of the scene's block).
            pub bvh: &'a crate::gpu::bvh::GpuBvh,
            $($(#[$bmeta])* pub $name: resource_ty!('a $kind),)*
        }
    };
    (none; $($(#[$bmeta:meta])* $name:ident : $kind:ident),*) => {
        /// The resources the kernel binds, by name.
        pub struct Resources<'a> {
            $($(#[$bmeta])* pub $name: resource_ty!('a $kind),)*
        }
    };
}

macro_rules! scene_use {
    (full) => {
        crate::gpu::kernel::SceneUse::Full
    };
    (bvh) => {
        crate::gpu::kernel::SceneUse::Bvh
    };
    (none) => {
        crate::gpu::kernel::SceneUse::None
    };
}

macro_rules! scene_descriptors {
    (full, $self:ident) => {
        $self.scene.resources().descriptors()
    };
    (bvh, $self:ident) => {
        $self.bvh.descriptors().to_vec()
    };
    (none, $self:ident) => {
        Vec::new()
    };
}

macro_rules! kernels {
    ($family:ident; $($(#[$meta:meta])* $role:ident $kernel:ident {
        scene: $scene:ident $([$($feature:ident),* $(,)?])?,
        push: $push:ty,
        local: [$lx:expr, $ly:expr, $lz:expr],
        spec: { $($spec:ident : $sty:tt = $sdef:expr),* $(,)? },
        bindings: { $($(#[$bmeta:meta])* $name:ident : $access:ident $kind:ident $arg:tt),* $(,)? }
    })*) => {
        mod $family {
            $(gated!($role,
                $(#[$meta])*
                #[allow(unused_imports)]
                pub mod $kernel {
                    use super::super::*;
                    use crate::gpu::kernel::{KernelInterface, SpecValue};

                    resources_struct!($scene; $($(#[$bmeta])* $name : $kind),*);

                    impl<'a> crate::gpu::kernel::BindResources<'a> for Resources<'a> {
                        fn descriptors(&self) -> Vec<crate::vk::Descriptor<'a>> {
                            let mut d = scene_descriptors!($scene, self);
                            $(d.extend(descriptors!($kind $arg, self.$name));)*
                            d
                        }
                    }

                    /// The kernel's push constants.
                    pub type Push = $push;

                    /// The kernel's workgroup size (build.rs declares it in the GLSL).
                    pub const LOCAL: [u32; 3] = [$lx, $ly, $lz];

                    const _: () = assert!(
                        std::mem::size_of::<$push>() <= MAX_PUSH_CONSTANT_BYTES as usize,
                        concat!("kernel ", stringify!($kernel), ": push constants over MAX_PUSH_CONSTANT_BYTES")
                    );

                    /// The kernel's own specialization constants (the scene's features come from
                    /// the scene).
                    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
                    pub struct Spec {
                        $(#[doc = concat!("`", stringify!($spec), "` (upper case in GLSL).")] pub $spec: rust_ty!($sty),)*
                    }

                    impl Default for Spec {
                        fn default() -> Self {
                            Self { $($spec: $sdef,)* }
                        }
                    }

                    impl crate::gpu::kernel::SpecValues for Spec {
                        fn values(&self) -> Vec<u32> {
                            vec![$(SpecValue::to_u32(self.$spec)),*]
                        }
                    }

                    /// The kernel's interface.
                    pub static INTERFACE: KernelInterface = KernelInterface {
                        name: stringify!($kernel),
                        scene: scene_use!($scene),
                        feature_list: &[$($(stringify!($feature)),*)?],
                        bindings: &[$(binding_descs!($name, $access $kind $arg)),*],
                        push_type: stringify!($push),
                        push_size: std::mem::size_of::<$push>() as u32,
                        local: LOCAL,
                        spec: &[$(SpecDesc { name: stringify!($spec), ty: stringify!($sty) }),*],
                    };

                    /// The kernel as a type, for [`crate::gpu::kernel::Pipeline`].
                    pub struct Kernel;

                    impl crate::gpu::kernel::Kernel for Kernel {
                        type Resources<'a> = Resources<'a>;
                        type Push = $push;
                        type Spec = Spec;
                        const LOCAL: [u32; 3] = LOCAL;
                        const INTERFACE: &'static KernelInterface = &INTERFACE;
                    }
                }
            );)*

            /// The family's kernels' interfaces, in order.
            #[allow(clippy::vec_init_then_push)] // some pushes are cfg'd out
            pub(super) fn all() -> Vec<&'static crate::gpu::kernel::KernelInterface> {
                let mut all = Vec::new();
                $(gated_statement!($role, all.push(&$kernel::INTERFACE));)*
                all
            }
        }
    };
}

/// The families of kernels `interface.rs` includes, in order.
macro_rules! kernel_families {
    ($($family:ident),* $(,)?) => {
        /// One module per kernel of `spirv/`: its resources by name ([`Resources`]), push
        /// constants ([`Push`]), specialization constants ([`Spec`]) and interface (what the
        /// pipeline layout and the naga test read).
        ///
        /// [`Resources`]: crate::gpu::kernels::pathtrace::Resources
        /// [`Push`]: crate::gpu::kernels::pathtrace::Push
        /// [`Spec`]: crate::gpu::kernels::pathtrace::Spec
        pub mod kernels {
            $(pub use super::$family::*;)*

            /// Every kernel's interface (the test kernels' with the `testing` feature).
            pub fn all() -> Vec<&'static crate::gpu::kernel::KernelInterface> {
                let mut all = Vec::new();
                $(all.extend(super::$family::all());)*
                all
            }
        }
    };
}

include!("interface.rs");

// The kernels' binding wall is the push descriptors a device must offer.
const _: () = assert!(MAX_KERNEL_BINDINGS == crate::vk::REQUIRED_PUSH_DESCRIPTORS);

/// The Rust type of [`GpuMaterial::tex_transform`]: its 40 rows (two per texture slot). A newtype
/// because the standard library derives `Default` only for arrays of up to 32 elements.
#[repr(transparent)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexTransforms(pub [[f32; 4]; 2 * MATERIAL_TEXTURE_SLOTS as usize]);

impl Default for TexTransforms {
    fn default() -> Self {
        Self([[0.0; 4]; 2 * MATERIAL_TEXTURE_SLOTS as usize])
    }
}

// SAFETY: a transparent wrapper of an array of `f32`s: no padding, every bit pattern valid.
unsafe impl Zeroable for TexTransforms {}
// SAFETY: as above.
unsafe impl Pod for TexTransforms {}

/// One member of a GPU struct as the host lays it out.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MemberLayout {
    /// Field name, identical to the GLSL member name.
    pub name: &'static str,
    /// Byte offset.
    pub offset: usize,
    /// Byte size.
    pub size: usize,
}

/// A GPU struct as the host lays it out.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StructLayout {
    /// Type name, identical to the GLSL struct name.
    pub name: &'static str,
    /// `size_of`, which is also the stride of an array of it.
    pub size: usize,
    /// Members in declaration order.
    pub members: Vec<MemberLayout>,
}

const _: () = assert!(size_of::<GpuCamera>() == 64);
const _: () = assert!(size_of::<GpuBvhNode>() == 64);
const _: () = assert!(size_of::<BvhTri>() == 48);
const _: () = assert!(size_of::<TraceRay>() == 32);
const _: () = assert!(size_of::<TraceHit>() == 16);
const _: () = assert!(size_of::<GpuTriangle>() == 32);
const _: () = assert!(size_of::<GpuVertex>() == 48);
const _: () = assert!(size_of::<GpuMaterial>() == 912);
const _: () = assert!(size_of::<TexTransforms>() == 16 * 2 * MATERIAL_TEXTURE_SLOTS as usize);
const _: () = assert!(5 * 4 == MATERIAL_TEXTURE_SLOTS as usize);
const _: () = assert!(size_of::<GpuTexture>() == 32);
const _: () = assert!(size_of::<GpuLightTri>() == 16);
const _: () = assert!(size_of::<GpuLight>() == 64);
const _: () = assert!(size_of::<GpuShadowLayer>() == 16 * SHADOW_LAYER_TEXELS as usize);
// Push constants: at most 128 bytes, the least every Vulkan device offers.
const _: () = assert!(size_of::<PathParams>() == 128);
const _: () = assert!(size_of::<DeferredParams>() == 128);
const _: () = assert!(size_of::<GBufferParams>() == 80);
const _: () = assert!(size_of::<AoParams>() == 112);
const _: () = assert!(size_of::<AoBlurParams>() == 96);
const _: () = assert!(size_of::<TaaParams>() == 96);
const _: () = assert!(size_of::<TemporalParams>() == 128);
const _: () = assert!(size_of::<IblParams>() == 48);
#[cfg(feature = "testing")]
const _: () = assert!(size_of::<LightTestParams>() == 64);
#[cfg(feature = "testing")]
const _: () = assert!(size_of::<SampleTestParams>() == 64);

impl TraceHit {
    /// `tri` of a ray that hit nothing.
    pub const MISS: u32 = u32::MAX;
}

impl GpuMaterial {
    /// [`MATERIAL_DOUBLE_SIDED`].
    pub const DOUBLE_SIDED: u32 = MATERIAL_DOUBLE_SIDED;
    /// [`MATERIAL_VOLUME`]: transmission refracts (`KHR_materials_volume`).
    pub const VOLUME: u32 = MATERIAL_VOLUME;
    /// [`MATERIAL_UNLIT`]: `KHR_materials_unlit`.
    pub const UNLIT: u32 = MATERIAL_UNLIT;
}

impl GpuTexture {
    /// [`TEXTURE_WRAP_S_CLAMP`].
    pub const WRAP_S_CLAMP: u32 = TEXTURE_WRAP_S_CLAMP;
    /// [`TEXTURE_WRAP_S_MIRROR`].
    pub const WRAP_S_MIRROR: u32 = TEXTURE_WRAP_S_MIRROR;
    /// [`TEXTURE_WRAP_T_CLAMP`].
    pub const WRAP_T_CLAMP: u32 = TEXTURE_WRAP_T_CLAMP;
    /// [`TEXTURE_WRAP_T_MIRROR`].
    pub const WRAP_T_MIRROR: u32 = TEXTURE_WRAP_T_MIRROR;
    /// [`TEXTURE_LINEAR`] (bilinear magnification; otherwise nearest).
    pub const LINEAR: u32 = TEXTURE_LINEAR;
    /// [`TEXTURE_SRGB`] (sRGB-encoded colour, decoded at upload).
    pub const SRGB: u32 = TEXTURE_SRGB;
    /// [`TEXTURE_MIN_LINEAR`] (bilinear within a level when minified; otherwise nearest).
    pub const MIN_LINEAR: u32 = TEXTURE_MIN_LINEAR;
    /// [`TEXTURE_MIP_LINEAR`] (blend the two nearest mip levels; otherwise the nearest level).
    pub const MIP_LINEAR: u32 = TEXTURE_MIP_LINEAR;
}

impl GpuLight {
    /// [`LIGHT_POINT`].
    pub const POINT: f32 = LIGHT_POINT;
    /// [`LIGHT_SPOT`].
    pub const SPOT: f32 = LIGHT_SPOT;
    /// [`LIGHT_DIRECTIONAL`].
    pub const DIRECTIONAL: f32 = LIGHT_DIRECTIONAL;
}

/// The stages of `pathtrace.comp` whose value first went NaN or infinite, bit 0 first
/// ([`PathStats::nonfinite_sources`]).
pub const NONFINITE_SOURCES: [&str; 7] = [
    "environment",
    "emission",
    "emissive NEE",
    "punctual lights",
    "environment NEE",
    "BSDF sample weight",
    "first-hit RIS",
];

/// The names of the stages set in a `nonfinite_sources` mask.
pub fn nonfinite_source_names(mask: u32) -> Vec<&'static str> {
    NONFINITE_SOURCES.iter().enumerate().filter(|(i, _)| mask & (1 << i) != 0).map(|(_, n)| *n).collect()
}

impl GpuCamera {
    /// `camera` for an image of `size` (`camera.glsl`), rendered whole.
    pub fn new(camera: &crate::scene::Camera, size: (u32, u32)) -> Self {
        Self::region(camera, size, (0, 0))
    }

    /// `camera` for an image of `size` of which a kernel renders the region from pixel `origin`
    /// on (both coordinates below 65,536: umbra's images are at most 16,384 on a side).
    pub fn region(camera: &crate::scene::Camera, (w, h): (u32, u32), origin: (u32, u32)) -> Self {
        use glam::Vec3;
        let forward = Vec3::from(camera.forward).normalize();
        let right = forward.cross(Vec3::from(camera.up)).normalize();
        let up = right.cross(forward);
        // Pinhole: the half extents at depth 1 (tan(yfov/2) × aspect, tan(yfov/2)).
        let (half_w, half_h) = camera.half_extent(1.0, w as f32 / h as f32);
        let mut gpu = Self {
            origin: camera.position,
            forward: forward.into(),
            right: (right * half_w).into(),
            up: (up * half_h).into(),
            image_width: w,
            image_height: h,
            flags: if camera.orthographic.is_some() { CAMERA_ORTHOGRAPHIC } else { 0 },
            ..Default::default()
        };
        gpu.set_region_origin(origin);
        gpu.set_jitter(camera.jitter);
        gpu
    }

    /// Whether the camera is orthographic (else a pinhole).
    pub fn orthographic(&self) -> bool {
        self.flags & CAMERA_ORTHOGRAPHIC != 0
    }

    /// The sub-pixel offset of every pixel's sample position from its centre, pixels (x right,
    /// y down), as the kernels read it: a multiple of 1/4096 in [-0.5, 0.5).
    pub fn jitter(&self) -> [f32; 2] {
        // Each a signed 12-bit field: shifted to the word's top and back, sign-extended.
        let field = |shift: u32| ((self.flags << (20 - shift)) as i32 >> 20) as f32 * CAMERA_JITTER_UNIT;
        [field(8), field(20)]
    }

    /// Sets the sub-pixel offset of every pixel's sample position ([`GpuCamera::jitter`]),
    /// rounded to the nearest 1/4096 pixel; each coordinate must lie in [-0.5, 0.5) (an offset
    /// of a whole pixel moves the image: move the camera instead).
    pub fn set_jitter(&mut self, jitter: [f32; 2]) {
        let field = |j: f32| {
            let q = (j / CAMERA_JITTER_UNIT).round();
            debug_assert!((-2048.0..2048.0).contains(&q), "jitter {j} outside [-0.5, 0.5)");
            (q.clamp(-2048.0, 2047.0) as i32 as u32) & 0xfff
        };
        self.flags = (self.flags & 0xff) | field(jitter[0]) << 8 | field(jitter[1]) << 20;
    }

    /// The region's first pixel (left column, top row).
    pub fn region_origin(&self) -> (u32, u32) {
        (self.region & 0xffff, self.region >> 16)
    }

    /// Moves the region to start at pixel `origin` (left column, top row; each below 65,536).
    pub fn set_region_origin(&mut self, (x, y): (u32, u32)) {
        debug_assert!(x < 1 << 16 && y < 1 << 16, "region origin {x},{y} beyond 65,535");
        self.region = x | y << 16;
    }
}

impl PathStats {
    /// The path segments counted, both words joined.
    pub fn segments(&self) -> u64 {
        (self.segments_hi as u64) << 32 | self.segments_lo as u64
    }

    /// With lane counts ([`crate::passes::pathtrace::PathTarget::with_lane_counts`]), the share
    /// of the SIMD lanes that the BVH walks of the closest-hit traces (`any_hit` false) or of the
    /// any-hit traces (shadow rays) kept busy: the lanes' walk-loop iterations over the groups'
    /// times `subgroup_size`. `None` where no such trace was counted.
    pub fn busy_lanes(&self, any_hit: bool, subgroup_size: u32) -> Option<f64> {
        let [lanes_closest, groups_closest, lanes_any, groups_any] = self.walk_counts();
        let (lanes, groups) = if any_hit { (lanes_any, groups_any) } else { (lanes_closest, groups_closest) };
        (groups > 0).then(|| lanes as f64 / (groups as f64 * subgroup_size as f64))
    }

    /// The lane counts, both words of each joined: the closest-hit traces' lane and group
    /// iterations, then the any-hit traces'.
    pub fn walk_counts(&self) -> [u64; 4] {
        [self.walk_lanes_closest, self.walk_groups_closest, self.walk_lanes_any, self.walk_groups_any]
            .map(|[lo, hi]| (hi as u64) << 32 | lo as u64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The jitter's fields keep their sign and the orthographic bit, and round to 1/4096 pixel.
    #[test]
    fn camera_jitter_round_trips() {
        let mut camera = GpuCamera { flags: CAMERA_ORTHOGRAPHIC, ..Default::default() };
        for jitter in [[0.0, 0.0], [0.25, -0.25], [-0.5, 0.5 - 1.0 / 4096.0], [0.1, -0.3]] {
            camera.set_jitter(jitter);
            let back = camera.jitter();
            for k in 0..2 {
                assert!((back[k] - jitter[k]).abs() <= 0.5 / 4096.0, "{jitter:?} came back as {back:?}");
            }
            assert!(camera.orthographic(), "the jitter cleared the orthographic bit");
        }
        camera.set_jitter([0.0, 0.0]);
        assert_eq!(camera.flags, CAMERA_ORTHOGRAPHIC, "no jitter is no bits");
    }
}
