#version 460
// One prefiltered level (ibl.glsl) of perceptual roughness `roughness`: per texel direction r,
// n = v = r, `samples` Hammersley samples of GGX visible normals, sum L(l) n.l / sum n.l, with
// filtered importance sampling (Krivanek and Colbert 2008): each sample reads the box chain at
// the level whose texels cover its share of the solid angle, 1 / (samples * pdf).
#extension GL_GOOGLE_include_directive : require
#include "kernel/ibl_prefilter.glsl"

KERNEL_LOCAL_SIZE;

#include "environment.glsl"
#include "ibl.glsl"

vec3 chain_bilinear(uint k, vec2 uv) {
    uvec2 size = chain_size(k, params.src_size);
    uvec4 idx;
    vec4 w;
    equirect_taps(uv, size, idx, w);
    if (k == 0u) {
        return w.x * env_value(idx.x).rgb + w.y * env_value(idx.y).rgb + w.z * env_value(idx.z).rgb +
               w.w * env_value(idx.w).rgb;
    }
    uint o = chain_offset(k, params.src_size);
    return w.x * chain[o + idx.x].rgb + w.y * chain[o + idx.y].rgb + w.z * chain[o + idx.z].rgb +
           w.w * chain[o + idx.w].rgb;
}

void main() {
    uvec2 xy = gl_GlobalInvocationID.xy;
    uvec2 size = params.dst_size;
    if (any(greaterThanEqual(xy, size))) {
        return;
    }
    uvec2 src = params.src_size;
    vec3 r = env_direction((vec2(xy) + 0.5) / vec2(size));
    vec3 t;
    vec3 b;
    basis(r, t, b);
    float roughness = params.roughness;
    float a = max(roughness * roughness, 1e-4);
    uint count = params.samples;
    uint levels = chain_levels(src);
    // Solid angle of a source texel is (2 pi / W)(pi / H) sin(theta).
    float texel = 2.0 * PI * PI / float(src.x * src.y);
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    for (uint i = 0u; i < count; ++i) {
        vec3 h = sample_ggx_vndf(vec3(0.0, 0.0, 1.0), a, hammersley(i, count));
        vec3 l = vec3(2.0 * h.z * h.x, 2.0 * h.z * h.y, 2.0 * h.z * h.z - 1.0);
        if (l.z <= 0.0) {
            continue;
        }
        vec3 lw = l.x * t + l.y * b + l.z * r;
        // With v = n the visible-normal density of l is D(h) / 4.
        float pdf = 0.25 * ggx_d(h, a);
        float sin_theta = max(sqrt(max(0.0, 1.0 - lw.y * lw.y)), 1e-4);
        // The level whose texels match the sample's solid angle 1 / (count pdf), minus 1.5: a
        // bilinear read of level k already averages a tent two texels wide (4 texels' area,
        // one level), and the blend between levels half a level more on average. (Krivanek
        // and Colbert's +1 bias blurred a bright disc up to 63 % beyond the GGX integral;
        // tests/ibl/ prefiltered_levels_match_brute_force measures this choice.)
        float lod = 0.5 * log2(1.0 / (float(count) * pdf * texel * sin_theta)) - 1.5;
        lod = clamp(lod, 0.0, float(levels - 1u));
        uint k0 = uint(lod);
        uint k1 = min(k0 + 1u, levels - 1u);
        vec2 uv = env_uv(lw);
        vec3 radiance = mix(chain_bilinear(k0, uv), chain_bilinear(k1, uv), lod - float(k0));
        sum += radiance * l.z;
        weight += l.z;
    }
    prefiltered[params.dst_offset + xy.y * size.x + xy.x] = vec4(weight > 0.0 ? sum / weight : vec3(0.0), 1.0);
}
