#version 460
// Ray-traced ambient occlusion over a G-buffer: the ground truth ssao.comp approximates.
//
// AO(p) = (1/π) ∫ V_r(p, ω) cos θ dω: the cosine-weighted fraction of the hemisphere around the
// shading normal whose rays leave p without meeting geometry within the radius r. `counts.x`
// cosine-distributed rays per pixel (random numbers from (pixel, frame * rays + i, seed)), each an
// any-hit query through the BVH over (0, r) from the origin offset off the geometric surface as
// shadow rays are (shading.glsl). A direction below the geometric surface counts as occluded (the
// surface itself blocks it). The output is the fraction of unoccluded rays, an unbiased estimate
// of AO(p) with variance AO(1 − AO) / rays. Pixels without a surface get 1. Alpha-masked and
// blended surfaces occlude as the path tracer sees them (shading.glsl's alpha test).
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"
#include "pixel.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(constant_id = 0) const bool HAS_TEXTURES = false;
layout(constant_id = 1) const bool HAS_ALPHA = false;
const bool BECKMANN = false;
const bool HAS_TRANSMISSION = false;

// Bindings 0-8 as gbuffer.comp's (GpuScene::SURFACE_BINDINGS): the BVH and what shading.glsl's
// alpha test reads, so alpha-masked and blended surfaces occlude as the path tracer sees them.
layout(set = 0, binding = 0, rgba32ui) uniform readonly uimageBuffer bvh_node_texels;
layout(set = 0, binding = 1, rgba32ui) uniform readonly uimageBuffer bvh_tri_texels;
layout(set = 0, binding = 2, std430) readonly buffer Triangles { GpuTriangle triangles[]; };
layout(set = 0, binding = 3, std430) readonly buffer Vertices { GpuVertex vertices[]; };
layout(set = 0, binding = 4, std430) readonly buffer Materials { GpuMaterial materials[]; };
layout(set = 0, binding = 5, std430) readonly buffer Textures { GpuTexture textures[]; };
layout(set = 0, binding = 6, r32ui) uniform readonly uimageBuffer scene_texels;
layout(set = 0, binding = 7, std430) readonly buffer Lights { GpuLightTri lights[]; };
layout(set = 0, binding = 8, std430) readonly buffer Punctual { GpuLight punctual[]; };
layout(set = 0, binding = 9, r32f) uniform readonly image2D gb_depth;
layout(set = 0, binding = 10, rgba16f) uniform readonly image2D gb_normal;
layout(set = 0, binding = 11, rg32ui) uniform readonly uimage2D gb_material;
layout(set = 0, binding = 12, r32f) uniform image2D out_ao;
layout(push_constant) uniform Push { AoParams params; };

#include "random.glsl"
#include "sampling.glsl"
#include "gbuffer.glsl"
#include "shading.glsl"

void main() {
    ivec2 pixel = ivec2(tile_pixel());
    uvec2 size = params.size_frame.xy;
    if (any(greaterThanEqual(uvec2(pixel), size))) {
        return;
    }
    float depth = imageLoad(gb_depth, pixel).x;
    // Rays [first, first + batch) of the pixel's `rays` (counts.z, counts.w): one dispatch per
    // batch, each adding its rays' share, so no invocation runs long enough for llvmpipe's loop
    // limiter (65,535 loop iterations per invocation, then every loop breaks) to cut it short.
    uint rays = max(params.counts.x, 1u);
    uint first = params.counts.z;
    uint last = min(first + max(params.counts.w, 1u), rays);
    if (depth <= 0.0) {
        imageStore(out_ao, pixel, vec4(1.0));
        return;
    }
    vec3 p = gbuffer_position(params.cam_origin.xyz, params.cam_forward.xyz, params.cam_right.xyz,
                              params.cam_up.xyz, pixel, size, depth);
    vec3 n = normalize(imageLoad(gb_normal, pixel).xyz);
    vec3 ng = oct_decode(unpackSnorm2x16(imageLoad(gb_material, pixel).y));
    vec3 o = offset_ray(p, ng);
    float radius = params.radius_bias.x;
    vec3 t;
    vec3 b;
    basis(n, t, b);
    uint open = 0u;
    for (uint i = first; i < last; ++i) {
        vec2 u = rand4(uvec2(pixel), params.size_frame.z * rays + i, 0u, params.size_frame.w).xy;
        vec3 w = sample_cosine_hemisphere(u);
        vec3 dir = w.x * t + w.y * b + w.z * n;
        if (dot(dir, ng) > 0.0 && !bvh_any(o, dir, 0.0, radius)) {
            open += 1u;
        }
    }
    float before = first > 0u ? imageLoad(out_ao, pixel).x : 0.0;
    imageStore(out_ao, pixel, vec4(before + float(open) / float(rays)));
}
