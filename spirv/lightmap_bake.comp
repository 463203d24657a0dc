#version 460
// One sample of every lightmap texel's irradiance (src/passes/lightmap.rs), into two running
// means: `emitters`, the direct irradiance from the emissive triangles (one light sample with its
// shadow ray: light sampling alone, unbiased for direct light), and `ambient`, the irradiance from
// everything else but the punctual lights' direct light — the environment and the light surfaces
// reflect — from one cosine-distributed gather ray (gather.glsl: the hit's direct light, and the
// probe volume's irradiance for the bounces beyond when one is bound). The irradiance estimates:
// L cos / pdf for the light sample, pi L for the gather ray (pdf = cos / pi). Each mean keeps the
// mean square of its red channel beside it, for the estimate's standard error.
//
// Specialised for `occlusion`, it bakes an ambient-occlusion map instead: the running mean of
// the visibility of one cosine-distributed ray of length `radius` (RTAO's estimator, the ground
// truth of src/passes/ao.rs), for glTF's occlusionTexture.
#extension GL_GOOGLE_include_directive : require
#include "kernel/lightmap_bake.glsl"

KERNEL_LOCAL_SIZE;

const bool BECKMANN = false;
const bool GGX_WALTER = false;

#include "random.glsl"
#include "gbuffer.glsl"
#include "environment.glsl"
#include "shading.glsl"
#include "probes.glsl"
#include "gather.glsl"

// Streams beside gather.glsl's (0 and 1).
const uint RNG_LIGHTMAP_EMITTERS = 2u;
const uint RNG_LIGHTMAP_GATHER = 3u;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.texel_count) {
        return;
    }
    vec4 pos = imageLoad(lightmap_texels, int(2u * i));
    if (pos.w == 0.0) {
        return;
    }
    vec3 p = pos.xyz;
    vec3 n = imageLoad(lightmap_texels, int(2u * i + 1u)).xyz;
    vec3 t;
    vec3 b;
    basis(n, t, b);
    uvec2 key = uvec2(i, 0x4c4du);
    uint sample_index = params.sample_index;

    if (OCCLUSION) {
        vec4 u = rand4(key, sample_index, RNG_LIGHTMAP_GATHER, params.seed);
        vec3 d = sample_cosine_hemisphere(u.xy);
        vec3 dir = normalize(d.x * t + d.y * b + d.z * n);
        float open = bvh_any(offset_ray(p, n), dir, 0.0, params.radius) ? 0.0 : 1.0;
        float old = sample_index == 0u ? 0.0 : lightmap_accum[2u * i].x;
        lightmap_accum[2u * i] = vec4(old + (open - old) / float(sample_index + 1u), 0.0, 0.0, 0.0);
        return;
    }

    vec3 emitters = vec3(0.0);
    if (HAS_LIGHTS && params.light_count > 0u) {
        vec4 u = rand4(key, sample_index, RNG_LIGHTMAP_EMITTERS, params.seed);
        vec3 wi_local;
        vec3 l_emit;
        float light_pdf;
        if (sample_emissive(p, n, t, b, n, false, u.xyz, params.light_count, wi_local, l_emit, light_pdf)) {
            emitters = l_emit * wi_local.z / light_pdf;
        }
    }

    vec4 u = rand4(key, sample_index, RNG_LIGHTMAP_GATHER, params.seed);
    vec3 d = sample_cosine_hemisphere(u.xy);
    vec3 dir = normalize(d.x * t + d.y * b + d.z * n);
    bool back_face;
    float hit_t;
    vec3 radiance = gather_radiance(offset_ray(p, n), dir, params.env, params.env_size, params.light_count,
                                    params.punctual_count, key, sample_index, params.seed, back_face, hit_t);
    vec3 ambient = PI * radiance;

    float k = float(sample_index + 1u);
    vec4 e_old = sample_index == 0u ? vec4(0.0) : lightmap_accum[2u * i];
    vec4 a_old = sample_index == 0u ? vec4(0.0) : lightmap_accum[2u * i + 1u];
    vec4 e_new = vec4(emitters, emitters.r * emitters.r);
    vec4 a_new = vec4(ambient, ambient.r * ambient.r);
    lightmap_accum[2u * i] = e_old + (e_new - e_old) / k;
    lightmap_accum[2u * i + 1u] = a_old + (a_new - a_old) / k;
}
