#version 460
// One update of a range of irradiance probes, second half (src/passes/probes.rs): one workgroup per
// probe folds the rays probe_trace.comp traced into the probe's octahedral maps. Each invocation
// owns a texel of the distance map (and the first PROBE_IRRADIANCE_SIDE² also one of the irradiance
// map), border texels included (probes.glsl: a border texel stands for the interior texel across
// the edge, so it computes the same value). Irradiance is pi times the cosine-weighted mean of the
// rays' radiance about the texel's direction (a ratio estimator, exact for constant radiance);
// distance the mean and mean square of the rays' distances weighed by cos^DISTANCE_SHARPNESS. A
// probe's first `warmup` updates replace its maps (each adds a bounce of light: the trace reads the
// volume); later ones blend the new estimate in with weight max(blend_min, 1 / (updates since the
// last replacement + 1)): a running mean (blend_min 0) or, after its first 1 / blend_min updates,
// an exponential one (hysteresis 1 - blend_min). A probe with more than PROBE_BACKFACE_LIMIT of its
// rays on back faces is inside geometry and is switched off.
#extension GL_GOOGLE_include_directive : require
#include "kernel/probe_blend.glsl"

KERNEL_LOCAL_SIZE;

#include "sampling.glsl"
#include "gbuffer.glsl"
#include "probes.glsl"

const float DISTANCE_SHARPNESS = 50.0;
const float PROBE_BACKFACE_LIMIT = 0.25;

shared vec4 ray_dirs[PROBE_MAX_RAYS];
shared vec4 ray_values[PROBE_MAX_RAYS];
shared uint backfaces;

void main() {
    uint slot = gl_WorkGroupID.x;
    uint local = gl_LocalInvocationIndex;
    uint rays = params.rays;
    uvec3 counts = probe_counts();
    uint total = counts.x * counts.y * counts.z;
    uint probe = (params.first_probe + slot) % total;
    if (local == 0u) {
        backfaces = 0u;
    }
    barrier();
    for (uint r = local; r < rays; r += 256u) {
        vec4 v = probe_rays[slot * rays + r];
        ray_values[r] = v;
        ray_dirs[r] = vec4(probe_ray_direction(r, rays, params.rotation0.xyz, params.rotation1.xyz,
                                               params.rotation2.xyz), 0.0);
        if (v.w < 0.0) {
            atomicAdd(backfaces, 1u);
        }
    }
    barrier();

    uvec4 state = probe_state(probe);
    float alpha = state.w < params.warmup ? 1.0 : max(params.blend_min, 1.0 / float(state.y + 1u));
    uvec2 texel = gl_LocalInvocationID.xy;

    vec3 d = probe_texel_direction(texel, PROBE_DISTANCE_SIDE);
    vec2 moments = vec2(0.0);
    float weight = 0.0;
    for (uint r = 0u; r < rays; ++r) {
        float w = pow(max(dot(d, ray_dirs[r].xyz), 0.0), DISTANCE_SHARPNESS);
        float t = abs(ray_values[r].w);
        moments += w * vec2(t, t * t);
        weight += w;
    }
    int di = int(probe * PROBE_DISTANCE_SIDE * PROBE_DISTANCE_SIDE + texel.y * PROBE_DISTANCE_SIDE + texel.x);
    if (weight > 0.0) {
        vec2 old = imageLoad(probe_distance, di).rg;
        imageStore(probe_distance, di, vec4(alpha >= 1.0 ? moments / weight : mix(old, moments / weight, alpha), 0.0, 0.0));
    }

    if (all(lessThan(texel, uvec2(PROBE_IRRADIANCE_SIDE)))) {
        vec3 n = probe_texel_direction(texel, PROBE_IRRADIANCE_SIDE);
        vec3 sum = vec3(0.0);
        float cosines = 0.0;
        for (uint r = 0u; r < rays; ++r) {
            float c = max(dot(n, ray_dirs[r].xyz), 0.0);
            sum += c * ray_values[r].rgb;
            cosines += c;
        }
        int ii = int(probe * PROBE_IRRADIANCE_SIDE * PROBE_IRRADIANCE_SIDE + texel.y * PROBE_IRRADIANCE_SIDE + texel.x);
        if (cosines > 0.0) {
            vec3 old = imageLoad(probe_irradiance, ii).rgb;
            vec3 e = PI * sum / cosines;
            imageStore(probe_irradiance, ii, vec4(alpha >= 1.0 ? e : mix(old, e, alpha), 1.0));
        }
    }

    // Every invocation has read the state: the first one updates it.
    barrier();
    if (local == 0u) {
        bool inside = float(backfaces) > PROBE_BACKFACE_LIMIT * float(rays);
        uint updates = alpha >= 1.0 ? 1u : min(state.y + 1u, 0x7fffffffu);
        imageStore(probe_texels, int(PROBE_HEADER_TEXELS + probe),
                   uvec4(inside ? 0u : PROBE_ACTIVE, updates, backfaces, min(state.w + 1u, 0x7fffffffu)));
    }
}
