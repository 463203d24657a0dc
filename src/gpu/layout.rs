//! Rust twins of the structs in `spirv/include/layout.glsl`. `tests/layout.rs` compares every
//! member offset, size and array stride with the compiled SPIR-V, so neither side can drift.

pub use crate::bvh::gpu::GpuBvhNode;
pub use crate::bvh::{BvhNode, BvhTri};
use bytemuck::{Pod, Zeroable};
use std::mem::{offset_of, size_of};

/// Push constants of `test_pattern.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PatternParams {
    /// Image width and height.
    pub size: [u32; 2],
    /// Added to the hashed index.
    pub seed: u32,
    /// Added to the product channel.
    pub frame: u32,
}
const _: () = assert!(size_of::<PatternParams>() == 16);

/// Push constants of `test_buffer.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BufferTestParams {
    /// Number of elements.
    pub count: u32,
    /// Added to each tripled element.
    pub add: u32,
}
const _: () = assert!(size_of::<BufferTestParams>() == 8);

/// A ray for `trace.comp`: origin and `tmin`, direction and `tmax`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TraceRay {
    /// Origin xyz, `tmin` in w.
    pub origin_tmin: [f32; 4],
    /// Direction xyz (need not be normalised), `tmax` in w.
    pub dir_tmax: [f32; 4],
}
const _: () = assert!(size_of::<TraceRay>() == 32);

/// `trace.comp`'s answer for one ray.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TraceHit {
    /// Hit distance (closest-hit mode); 1.0 for occluded, 0.0 for clear in any-hit mode.
    pub t: f32,
    /// Triangle index in BVH order, [`TraceHit::MISS`] for none.
    pub tri: u32,
    /// Barycentric weight of the triangle's second vertex.
    pub u: f32,
    /// Barycentric weight of the triangle's third vertex.
    pub v: f32,
}
const _: () = assert!(size_of::<TraceHit>() == 16);

impl TraceHit {
    /// `tri` of a ray that hit nothing.
    pub const MISS: u32 = u32::MAX;
}

/// Push constants of `trace.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TraceParams {
    /// Number of rays.
    pub count: u32,
    /// Padding.
    pub pad0: u32,
    /// Padding.
    pub pad1: u32,
    /// Padding.
    pub pad2: u32,
}
const _: () = assert!(size_of::<TraceParams>() == 16);

/// A triangle of the GPU scene in BVH order (`GpuTriangle`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriangle {
    /// First vertex index.
    pub v0: u32,
    /// Second vertex index.
    pub v1: u32,
    /// Third vertex index.
    pub v2: u32,
    /// Material index.
    pub material: u32,
    /// Probability that light sampling picks this triangle (0 if it does not emit).
    pub light_pmf: f32,
    /// Area in square metres.
    pub area: f32,
    /// Padding.
    pub pad0: u32,
    /// Padding.
    pub pad1: u32,
}
const _: () = assert!(size_of::<GpuTriangle>() == 32);

/// Shading attributes of a vertex (`GpuVertex`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuVertex {
    /// Normal xyz, uv0.x.
    pub normal_u: [f32; 4],
    /// uv0.y, uv1.xy, unused.
    pub v_uv1: [f32; 4],
    /// Tangent xyz, bitangent sign (all 0 when the scene has no tangents).
    pub tangent: [f32; 4],
}
const _: () = assert!(size_of::<GpuVertex>() == 48);

/// A material's factors (`GpuMaterial`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    /// baseColorFactor.
    pub base_color: [f32; 4],
    /// Emission (strength applied) rgb, roughness.
    pub emissive_rough: [f32; 4],
    /// specularColorFactor rgb, specularFactor.
    pub specular: [f32; 4],
    /// metallic, ior, transmission, alpha cutoff.
    pub params: [f32; 4],
    /// `x`: [`GpuMaterial::DOUBLE_SIDED`] and other bits.
    pub flags: [u32; 4],
    /// Base colour, metallic-roughness, emissive, normal texture: index + 1 (0: none).
    pub textures: [u32; 4],
    /// Per slot two rows of the UV transform; the UV set in the first row's `w`; the normal
    /// slot's second row `w` is the normal scale.
    pub tex_transform: [[f32; 4]; 8],
}
const _: () = assert!(size_of::<GpuMaterial>() == 224);

impl GpuMaterial {
    /// `MATERIAL_DOUBLE_SIDED`.
    pub const DOUBLE_SIDED: u32 = 1;
    /// `MATERIAL_VOLUME`: transmission refracts (`KHR_materials_volume`).
    pub const VOLUME: u32 = 2;
}

/// A texture in the shared texel buffer (`GpuTexture`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTexture {
    /// First texel in the texel buffer.
    pub offset: u32,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// `TEXTURE_*` bits ([`GpuTexture::WRAP_S_CLAMP`], ...).
    pub flags: u32,
    /// Mip levels stored (1: level 0 only). Level k is `max(1, width >> k)` ×
    /// `max(1, height >> k)` texels and follows level k − 1 in the texel buffer.
    pub levels: u32,
    /// Padding to 32 bytes.
    pub pad0: u32,
    /// Padding.
    pub pad1: u32,
    /// Padding.
    pub pad2: u32,
}
const _: () = assert!(size_of::<GpuTexture>() == 32);

impl GpuTexture {
    /// `TEXTURE_WRAP_S_CLAMP`.
    pub const WRAP_S_CLAMP: u32 = 1;
    /// `TEXTURE_WRAP_S_MIRROR`.
    pub const WRAP_S_MIRROR: u32 = 2;
    /// `TEXTURE_WRAP_T_CLAMP`.
    pub const WRAP_T_CLAMP: u32 = 4;
    /// `TEXTURE_WRAP_T_MIRROR`.
    pub const WRAP_T_MIRROR: u32 = 8;
    /// `TEXTURE_LINEAR` (bilinear magnification; otherwise nearest).
    pub const LINEAR: u32 = 16;
    /// `TEXTURE_SRGB` (decode sRGB to linear).
    pub const SRGB: u32 = 32;
    /// `TEXTURE_MIN_LINEAR` (bilinear within a level when minified; otherwise nearest).
    pub const MIN_LINEAR: u32 = 64;
    /// `TEXTURE_MIP_LINEAR` (blend the two nearest mip levels; otherwise the nearest level).
    pub const MIP_LINEAR: u32 = 128;
}

/// One entry of the emissive-triangle sampling table (`GpuLightTri`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLightTri {
    /// Triangle in BVH order.
    pub tri: u32,
    /// Inclusive prefix of the normalised power.
    pub cdf: f32,
    /// Selection probability.
    pub pmf: f32,
    /// Area in square metres.
    pub area: f32,
}
const _: () = assert!(size_of::<GpuLightTri>() == 16);

/// A punctual light (`GpuLight`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    /// Position xyz, range (0: infinite).
    pub position_range: [f32; 4],
    /// Unit direction the light shines in, kind ([`GpuLight::POINT`], ...).
    pub direction_kind: [f32; 4],
    /// Colour × intensity (candela; lux for directional lights), inclusive prefix of the
    /// selection probabilities (by power).
    pub intensity: [f32; 4],
    /// cos(outer cone), 1 / max(cos(inner) − cos(outer), 1e-4), selection probability, unused.
    pub cone: [f32; 4],
}
const _: () = assert!(size_of::<GpuLight>() == 64);

impl GpuLight {
    /// `LIGHT_POINT`.
    pub const POINT: f32 = 0.0;
    /// `LIGHT_SPOT`.
    pub const SPOT: f32 = 1.0;
    /// `LIGHT_DIRECTIONAL`.
    pub const DIRECTIONAL: f32 = 2.0;
}

/// Push constants of `pathtrace.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PathParams {
    /// Camera position, unused.
    pub cam_origin: [f32; 4],
    /// Unit forward.
    pub cam_forward: [f32; 4],
    /// Right × tan(yfov/2) × aspect.
    pub cam_right: [f32; 4],
    /// Up × tan(yfov/2).
    pub cam_up: [f32; 4],
    /// Constant environment radiance rgb (or the environment map's multiplier), unused.
    pub env: [f32; 4],
    /// Width, height, sample index, seed.
    pub size_frame: [u32; 4],
    /// Max bounces, Russian-roulette depth, light triangles, punctual lights.
    pub settings: [u32; 4],
    /// Environment map width, height, next-event estimation on it (0/1), unused.
    pub env_info: [u32; 4],
}
const _: () = assert!(size_of::<PathParams>() == 128);

/// The stages of `pathtrace.comp` whose value first went NaN or infinite, bit 0 first
/// ([`PathStats::nonfinite_sources`]).
pub const NONFINITE_SOURCES: [&str; 6] =
    ["environment", "emission", "emissive NEE", "punctual lights", "environment NEE", "BSDF sample weight"];

/// The names of the stages set in a `nonfinite_sources` mask.
pub fn nonfinite_source_names(mask: u32) -> Vec<&'static str> {
    NONFINITE_SOURCES.iter().enumerate().filter(|(i, _)| mask & (1 << i) != 0).map(|(_, n)| *n).collect()
}

/// Counters written by `pathtrace.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PathStats {
    /// Samples that came out NaN or infinite (replaced by 0; must stay 0).
    pub nonfinite_samples: u32,
    /// Where they arose: bits of [`NONFINITE_SOURCES`].
    pub nonfinite_sources: u32,
    /// Padding.
    pub pad1: u32,
    /// Padding.
    pub pad2: u32,
}
const _: () = assert!(size_of::<PathStats>() == 16);

/// Push constants of `gbuffer.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GBufferParams {
    /// Camera position, unused.
    pub cam_origin: [f32; 4],
    /// Unit forward.
    pub cam_forward: [f32; 4],
    /// Right × tan(yfov/2) × aspect.
    pub cam_right: [f32; 4],
    /// Up × tan(yfov/2).
    pub cam_up: [f32; 4],
    /// Width, height, unused, unused.
    pub size: [u32; 4],
}
const _: () = assert!(size_of::<GBufferParams>() == 80);

/// Push constants of `deferred.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DeferredParams {
    /// Camera position, unused.
    pub cam_origin: [f32; 4],
    /// Unit forward.
    pub cam_forward: [f32; 4],
    /// Right × tan(yfov/2) × aspect.
    pub cam_right: [f32; 4],
    /// Up × tan(yfov/2).
    pub cam_up: [f32; 4],
    /// Constant environment radiance rgb (or the environment map's multiplier), unused.
    pub env: [f32; 4],
    /// Width, height, frame, seed.
    pub size_frame: [u32; 4],
    /// Light triangles, punctual lights, shadow rays per pixel for area lights, flags (1: IBL).
    pub counts: [u32; 4],
    /// Environment map width, height, unused, unused.
    pub env_info: [u32; 4],
}
const _: () = assert!(size_of::<DeferredParams>() == 128);

/// Push constants of `tonemap.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TonemapParams {
    /// Width, height.
    pub size: [u32; 2],
    /// Linear multiplier (2^stops).
    pub exposure: f32,
    /// [`crate::tonemap::ToneCurve::code`].
    pub curve: u32,
}
const _: () = assert!(size_of::<TonemapParams>() == 16);

/// Push constants of `ssao.comp` and `rtao.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct AoParams {
    /// Camera position, unused.
    pub cam_origin: [f32; 4],
    /// Unit forward.
    pub cam_forward: [f32; 4],
    /// Right × tan(yfov/2) × aspect.
    pub cam_right: [f32; 4],
    /// Up × tan(yfov/2).
    pub cam_up: [f32; 4],
    /// AO radius r (world units), SSAO plane bias (world units), unused, unused.
    pub radius_bias: [f32; 4],
    /// Width, height, frame, seed.
    pub size_frame: [u32; 4],
    /// Directions (SSAO) or rays (RTAO) per pixel, SSAO steps per direction, unused, unused.
    pub counts: [u32; 4],
}
const _: () = assert!(size_of::<AoParams>() == 112);

/// Push constants of `ao_blur.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct AoBlurParams {
    /// Unit forward.
    pub cam_forward: [f32; 4],
    /// Right × tan(yfov/2) × aspect.
    pub cam_right: [f32; 4],
    /// Up × tan(yfov/2).
    pub cam_up: [f32; 4],
    /// Plane-distance sigma (a fraction of the view depth), normal exponent, unused, unused.
    pub weights: [f32; 4],
    /// Width, height, unused, unused.
    pub size: [u32; 4],
}
const _: () = assert!(size_of::<AoBlurParams>() == 80);

/// Push constants of `light_sample_test.comp` (tests only).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct LightTestParams {
    /// Shading point xyz (world), unused.
    pub point: [f32; 4],
    /// Its unit normal xyz (world), unused.
    pub normal: [f32; 4],
    /// Mode, count, seed, variant (0 the renderer's pdf, 1 a deliberately wrong one).
    pub config: [u32; 4],
    /// Environment width, height, emissive-triangle count, unused.
    pub size: [u32; 4],
}
const _: () = assert!(size_of::<LightTestParams>() == 64);

/// The G-buffer's material index where no surface was hit (`GBUFFER_NO_SURFACE`).
pub const GBUFFER_NO_SURFACE: u32 = u32::MAX;

/// Push constants of `sample_test.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SampleTestParams {
    /// Outgoing direction (local frame) xyz, alpha.
    pub wo_alpha: [f32; 4],
    /// Mode (0 sample, 1 evaluate the pdf), count, seed, sampler (0 cosine, 1 microfacet).
    pub config: [u32; 4],
}
const _: () = assert!(size_of::<SampleTestParams>() == 32);

/// Push constants of the IBL precomputation kernels (`ibl_*.comp`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct IblParams {
    /// Source width, height (the environment map), level read (chain kernels), unused.
    pub src: [u32; 4],
    /// Level width, height, texel offset of the level written, samples (per axis for the LUT).
    pub dst: [u32; 4],
    /// Perceptual roughness of the level (prefilter), unused ×3.
    pub values: [f32; 4],
}
const _: () = assert!(size_of::<IblParams>() == 48);

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

macro_rules! layout_of {
    ($t:ident { $($field:ident),* $(,)? }) => {{
        let zero = <$t as Zeroable>::zeroed();
        StructLayout {
            name: stringify!($t),
            size: size_of::<$t>(),
            members: vec![$(MemberLayout {
                name: stringify!($field),
                offset: offset_of!($t, $field),
                size: std::mem::size_of_val(&zero.$field),
            }),*],
        }
    }};
}

/// Every host/GPU struct pair.
pub fn gpu_layouts() -> Vec<StructLayout> {
    vec![
        layout_of!(PatternParams { size, seed, frame }),
        layout_of!(BufferTestParams { count, add }),
        layout_of!(GpuBvhNode { origin, step, lo, hi, child }),
        layout_of!(BvhTri { v0, v1, v2 }),
        layout_of!(TraceRay { origin_tmin, dir_tmax }),
        layout_of!(TraceHit { t, tri, u, v }),
        layout_of!(TraceParams { count, pad0, pad1, pad2 }),
        layout_of!(GpuTriangle { v0, v1, v2, material, light_pmf, area, pad0, pad1 }),
        layout_of!(GpuVertex { normal_u, v_uv1, tangent }),
        layout_of!(GpuMaterial {
            base_color,
            emissive_rough,
            specular,
            params,
            flags,
            textures,
            tex_transform
        }),
        layout_of!(GpuTexture { offset, width, height, flags, levels, pad0, pad1, pad2 }),
        layout_of!(SampleTestParams { wo_alpha, config }),
        layout_of!(GpuLightTri { tri, cdf, pmf, area }),
        layout_of!(PathParams {
            cam_origin,
            cam_forward,
            cam_right,
            cam_up,
            env,
            size_frame,
            settings,
            env_info
        }),
        layout_of!(PathStats { nonfinite_samples, nonfinite_sources, pad1, pad2 }),
        layout_of!(GBufferParams { cam_origin, cam_forward, cam_right, cam_up, size }),
        layout_of!(TonemapParams { size, exposure, curve }),
        layout_of!(DeferredParams {
            cam_origin,
            cam_forward,
            cam_right,
            cam_up,
            env,
            size_frame,
            counts,
            env_info
        }),
        layout_of!(GpuLight { position_range, direction_kind, intensity, cone }),
        layout_of!(AoParams { cam_origin, cam_forward, cam_right, cam_up, radius_bias, size_frame, counts }),
        layout_of!(AoBlurParams { cam_forward, cam_right, cam_up, weights, size }),
        layout_of!(IblParams { src, dst, values }),
        layout_of!(LightTestParams { point, normal, config, size }),
    ]
}
