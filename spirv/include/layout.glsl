// Every struct shared with the host. Each has a #[repr(C)] twin in src/gpu/layout.rs with the
// same name and member names; tests/layout.rs compares their offsets and strides through naga.
// std430 rules apply: keep members in vec4-sized groups.
#ifndef UMBRA_LAYOUT_GLSL
#define UMBRA_LAYOUT_GLSL

// Push constants of test_pattern.comp.
struct PatternParams {
    uvec2 size;
    uint seed;
    uint frame;
};

// Push constants of test_buffer.comp.
struct BufferTestParams {
    uint count;
    uint add;
};

// A GPU BVH node, 64 bytes (bvh.glsl reads it as four texels): a grid per axis (planes at
// origin + q * step), each child's box in 8-bit grid steps (lo[axis], hi[axis]: byte c is child
// c), and per child a word index << 4 | count (count 0 inner, 15 absent, else a leaf's).
struct GpuBvhNode {
    vec3 origin;
    float step[3];
    uint lo[3];
    uint hi[3];
    uint child[4];
};

// A triangle in BVH order; floatBitsToUint(v0.w) is its index before reordering.
struct BvhTri {
    vec4 v0;
    vec4 v1;
    vec4 v2;
};

// A ray for trace.comp (tests and the ray-throughput benchmark).
struct TraceRay {
    vec4 origin_tmin;
    vec4 dir_tmax;
};

// trace.comp's answer: tri == 0xffffffff for a miss; any-hit mode writes t = 0 or 1 only.
struct TraceHit {
    float t;
    uint tri;
    float u;
    float v;
};

// Push constants of trace.comp.
struct TraceParams {
    uint count;
    uint pad0;
    uint pad1;
    uint pad2;
};

// A triangle of the GPU scene, in BVH order: vertex indices, material, and its light-selection
// probability (0 for a triangle that does not emit).
struct GpuTriangle {
    uint v0;
    uint v1;
    uint v2;
    uint material;
    float light_pmf;
    float area;
    uint pad0;
    uint pad1;
};

// Shading attributes of a vertex (world space): normal and uv0.
struct GpuVertex {
    vec4 normal_u;   // normal xyz, uv0.x
    vec4 v_uv1;      // uv0.y, uv1.xy, unused
    vec4 tangent;    // tangent xyz, bitangent sign (0 when the scene has no tangents)
};

// A glTF metallic-roughness material (factors; textures come with the texture issue).
struct GpuMaterial {
    vec4 base_color;      // baseColorFactor
    vec4 emissive_rough;  // emissive * emissive_strength, roughness
    vec4 specular;        // specularColorFactor rgb, specularFactor
    vec4 params;          // metallic, ior, transmission, alpha cutoff
    uvec4 flags;          // x: MATERIAL_* bits
    // Texture slots (base colour, metallic-roughness, emissive, normal): index + 1 (0: none).
    uvec4 textures;
    // Per slot, the KHR_texture_transform rows (u' = row0 . (u, v, 1), v' = row1 . (u, v, 1));
    // the UV set (0 or 1) in row0.w; the normal slot's row1.w is the normal scale.
    vec4 tex_transform[8];
};

#define MATERIAL_DOUBLE_SIDED 1u
// KHR_materials_volume with a thickness: transmission refracts (else it is thin-walled).
#define MATERIAL_VOLUME 2u

// A texture in the shared texel buffer (RGBA8, one uint per texel, row-major).
struct GpuTexture {
    uint offset;
    uint width;
    uint height;
    uint flags;  // TEXTURE_* bits
    uint levels; // mip levels stored (1: level 0 only), each after the previous, sizes max(1, size >> k)
    uint pad0;
    uint pad1;
    uint pad2;
};

#define TEXTURE_WRAP_S_CLAMP 1u
#define TEXTURE_WRAP_S_MIRROR 2u
#define TEXTURE_WRAP_T_CLAMP 4u
#define TEXTURE_WRAP_T_MIRROR 8u
#define TEXTURE_LINEAR 16u
#define TEXTURE_SRGB 32u
#define TEXTURE_MIN_LINEAR 64u
#define TEXTURE_MIP_LINEAR 128u

// One emissive triangle in the light-sampling table.
struct GpuLightTri {
    uint tri;   // BVH order
    float cdf;  // inclusive prefix of the normalised power
    float pmf;
    float area;
};

// A KHR_lights_punctual light in world space.
struct GpuLight {
    vec4 position_range;   // position xyz, range (0: infinite)
    vec4 direction_kind;   // unit direction the light shines in, kind (LIGHT_*)
    vec4 intensity;        // colour * intensity (candela, or lux for directional), unused
    vec4 cone;             // cos(outer), 1 / max(cos(inner) - cos(outer), 1e-4), unused, unused
};

#define LIGHT_POINT 0.0
#define LIGHT_SPOT 1.0
#define LIGHT_DIRECTIONAL 2.0

// Push constants of pathtrace.comp.
struct PathParams {
    vec4 cam_origin;   // xyz, unused
    vec4 cam_forward;  // unit forward
    vec4 cam_right;    // right * tan(yfov/2) * aspect
    vec4 cam_up;       // up * tan(yfov/2)
    vec4 env;          // constant environment radiance rgb (or the map's multiplier), unused
    uvec4 size_frame;  // width, height, sample index, seed
    uvec4 settings;    // max bounces, russian roulette depth, light triangles, punctual lights
    uvec4 env_info;    // environment map width, height, sample it for NEE (0/1), unused
};

// Per-render counters written by pathtrace.comp.
struct PathStats {
    uint nonfinite_samples;
    uint nonfinite_sources;  // bits of pathtrace.comp's NONFINITE_* stages where they arose
    uint pad1;
    uint pad2;
};

// Push constants of gbuffer.comp.
struct GBufferParams {
    vec4 cam_origin;   // xyz, unused
    vec4 cam_forward;  // unit forward
    vec4 cam_right;    // right * tan(yfov/2) * aspect
    vec4 cam_up;       // up * tan(yfov/2)
    uvec4 size;        // width, height, unused, unused
};

// Push constants of deferred.comp.
struct DeferredParams {
    vec4 cam_origin;   // xyz, unused
    vec4 cam_forward;  // unit forward
    vec4 cam_right;    // right * tan(yfov/2) * aspect
    vec4 cam_up;       // up * tan(yfov/2)
    vec4 env;          // constant environment radiance rgb (or the map's multiplier), unused
    uvec4 size_frame;  // width, height, frame, seed
    uvec4 counts;      // light triangles, punctual lights, shadow rays per pixel for area lights, flags (1: IBL, 2: IBL along the dominant direction)
    uvec4 env_info;    // environment map width, height, unused, unused
};

// Push constants of tonemap.comp.
struct TonemapParams {
    uvec2 size;
    float exposure;  // linear multiplier (2^stops)
    uint curve;      // 0 clamp, 1 ACES (Hill's fit), 2 Khronos PBR Neutral
};

// Material index in the G-buffer where no surface was hit.
#define GBUFFER_NO_SURFACE 0xffffffffu

// Push constants of sample_test.comp (the sampling tests' kernel).
struct SampleTestParams {
    vec4 wo_alpha;   // outgoing direction xyz (local frame), alpha
    uvec4 config;    // mode (0 sample, 1 evaluate pdf), count, seed, sampler (0 cosine, 1 microfacet, 2-4 dielectric BSDF)
};

// Push constants of ssao.comp and rtao.comp.
struct AoParams {
    vec4 cam_origin;   // xyz, unused
    vec4 cam_forward;  // unit forward
    vec4 cam_right;    // right * tan(yfov/2) * aspect
    vec4 cam_up;       // up * tan(yfov/2)
    vec4 radius_bias;  // AO radius r (world units), SSAO plane bias (world units), unused, unused
    uvec4 size_frame;  // width, height, frame, seed
    uvec4 counts;      // directions (SSAO) or rays (RTAO) per pixel, SSAO steps per direction, RTAO: first ray and rays of this dispatch
};

// Push constants of ao_blur.comp.
struct AoBlurParams {
    vec4 cam_forward;  // unit forward
    vec4 cam_right;    // right * tan(yfov/2) * aspect
    vec4 cam_up;       // up * tan(yfov/2)
    vec4 weights;      // plane-distance sigma (fraction of the depth), normal exponent, unused, unused
    uvec4 size;        // width, height, unused, unused
};

// Push constants of the IBL precomputation kernels (ibl_*.comp).
struct IblParams {
    uvec4 src;     // source width, height (the environment map), level read (chain kernels), first row (ibl_sh)
    uvec4 dst;     // level width, height, texel offset of the level written, samples (per axis for the LUT)
    vec4 values;   // perceptual roughness of the level (prefilter), unused, unused, unused
};

// Push constants of light_sample_test.comp (tests only).
struct LightTestParams {
    vec4 point;    // shading point xyz (world), unused
    vec4 normal;   // its unit normal xyz (world), unused
    uvec4 config;  // mode, count, seed, variant (0 the renderer's pdf, 1 a deliberately wrong one)
    uvec4 size;    // environment width, height, emissive-triangle count, unused
};

#endif
