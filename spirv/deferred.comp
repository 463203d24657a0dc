#version 460
// Deferred lighting of the G-buffer (gbuffer.comp) with the path tracer's BSDF and lights:
// emission, punctual lights and emissive triangles with ray-traced shadows (area lights sampled,
// `counts.z` shadow rays per pixel, so shadows are soft), and image-based lighting, multiplied by
// ambient occlusion. One bounce: no indirect light beyond what IBL approximates.
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(constant_id = 0) const bool HAS_TEXTURES = false;
layout(constant_id = 1) const bool HAS_LIGHTS = false;
layout(constant_id = 2) const bool HAS_PUNCTUAL = false;
layout(constant_id = 3) const bool HAS_ENV_MAP = false;
layout(constant_id = 4) const bool BECKMANN = false;
// The hybrid passes shade reflection only (see src/passes/deferred.rs).
const bool HAS_TRANSMISSION = false;

layout(set = 0, binding = 0, std430) readonly buffer BvhNodes { BvhNode bvh_nodes[]; };
layout(set = 0, binding = 1, std430) readonly buffer BvhTris { BvhTri bvh_tris[]; };
layout(set = 0, binding = 2, std430) readonly buffer Triangles { GpuTriangle triangles[]; };
layout(set = 0, binding = 3, std430) readonly buffer Vertices { GpuVertex vertices[]; };
layout(set = 0, binding = 4, std430) readonly buffer Materials { GpuMaterial materials[]; };
layout(set = 0, binding = 5, std430) readonly buffer Lights { GpuLightTri lights[]; };
layout(set = 0, binding = 6, std430) readonly buffer Punctual { GpuLight punctual[]; };
layout(set = 0, binding = 7, std430) readonly buffer Textures { GpuTexture textures[]; };
layout(set = 0, binding = 8, std430) readonly buffer Texels { uint texels[]; };
layout(set = 0, binding = 9, std430) readonly buffer EnvTexels { vec4 env_texels[]; };
layout(set = 0, binding = 10, std430) readonly buffer EnvMarginal { float env_marginal[]; };
layout(set = 0, binding = 11, std430) readonly buffer EnvConditional { float env_conditional[]; };
layout(set = 0, binding = 12, r32f) uniform readonly image2D gb_depth;
layout(set = 0, binding = 13, rgba16f) uniform readonly image2D gb_normal;
layout(set = 0, binding = 14, rgba16f) uniform readonly image2D gb_base;
layout(set = 0, binding = 15, rgba16f) uniform readonly image2D gb_emission;
layout(set = 0, binding = 16, rg32ui) uniform readonly uimage2D gb_material;
layout(set = 0, binding = 17, rgba32f) uniform writeonly image2D out_color;
layout(push_constant) uniform Push { DeferredParams params; };

#include "random.glsl"
#include "gbuffer.glsl"
#include "environment.glsl"
#include "shading.glsl"

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    uvec2 size = params.size_frame.xy;
    if (any(greaterThanEqual(uvec2(pixel), size))) {
        return;
    }
    vec3 forward = params.cam_forward.xyz;
    vec3 dir = camera_ray(forward, params.cam_right.xyz, params.cam_up.xyz, vec2(pixel) + 0.5, size);
    float depth = imageLoad(gb_depth, pixel).x;
    if (depth <= 0.0) {
        // No surface: the environment seen directly.
        vec3 background = params.env.rgb;
        if (HAS_ENV_MAP) {
            background *= env_radiance(dir, params.env_info.xy);
        }
        imageStore(out_color, pixel, vec4(background, 1.0));
        return;
    }
    vec3 p = params.cam_origin.xyz + dir * (depth / dot(dir, forward));
    vec4 normal_rough = imageLoad(gb_normal, pixel);
    vec4 base_metal = imageLoad(gb_base, pixel);
    uvec2 mat = imageLoad(gb_material, pixel).xy;
    vec3 radiance = imageLoad(gb_emission, pixel).rgb;

    vec3 n = normalize(normal_rough.xyz);
    vec3 ng = oct_decode(unpackSnorm2x16(mat.y));
    vec3 wo = -dir;
    vec3 t;
    vec3 b;
    basis(n, t, b);
    vec3 wo_local = vec3(dot(wo, t), dot(wo, b), dot(wo, n));
    if (wo_local.z > 0.0) {
        Surface s = material_surface_from(mat.x, base_metal.rgb, base_metal.a, normal_rough.w);

        // Punctual lights: one shadow ray each.
        if (HAS_PUNCTUAL) {
            radiance += punctual_direct(p, ng, t, b, n, s, wo_local, params.counts.y);
        }

        // Emissive triangles: `counts.z` light samples (triangle by power, uniform point on it),
        // each with its shadow ray; light sampling alone, which is unbiased for direct light.
        if (HAS_LIGHTS && params.counts.x > 0u) {
            uint rays = max(params.counts.z, 1u);
            vec3 sum = vec3(0.0);
            for (uint r = 0u; r < rays; ++r) {
                vec4 u = rand4(uvec2(pixel), params.size_frame.z * rays + r, 1u, params.size_frame.w);
                vec3 wi_local;
                vec3 l_emit;
                float light_pdf;
                if (sample_emissive(p, ng, t, b, n, u.xyz, params.counts.x, wi_local, l_emit, light_pdf)) {
                    sum += bsdf_eval(s, wo_local, wi_local) * wi_local.z * l_emit / light_pdf;
                }
            }
            radiance += sum / float(rays);
        }
    }
    imageStore(out_color, pixel, vec4(radiance, 1.0));
}
