// Equirectangular environment lookup and importance sampling (src/environment.rs builds the
// tables). +Y is up; u = atan2(d.x, -d.z) / 2pi + 1/2, v = acos(d.y) / pi, row 0 at the top.
//
// The including kernel declares, before including this file:
//   readonly buffer ... { vec4 env_texels[]; };       // rgb radiance, density over (u, v)
//   readonly buffer ... { float env_marginal[]; };    // inclusive CDF over rows
//   readonly buffer ... { float env_conditional[]; }; // inclusive CDF within each row
// and passes the map's size.
#ifndef UMBRA_ENVIRONMENT_GLSL
#define UMBRA_ENVIRONMENT_GLSL

#include "sampling.glsl"

vec2 env_uv(vec3 d) {
    return vec2(atan(d.x, -d.z) * (0.5 * INV_PI) + 0.5, acos(clamp(d.y, -1.0, 1.0)) * INV_PI);
}

vec3 env_direction(vec2 uv) {
    float phi = (uv.x - 0.5) * 2.0 * PI;
    float theta = uv.y * PI;
    float s = sin(theta);
    return vec3(s * sin(phi), cos(theta), -s * cos(phi));
}

uint env_texel(vec2 uv, uvec2 size) {
    uvec2 xy = min(uvec2(uv * vec2(size)), size - 1u);
    return xy.y * size.x + xy.x;
}

// Radiance arriving along -d (looking towards d).
vec3 env_radiance(vec3 d, uvec2 size) {
    return env_texels[env_texel(env_uv(d), size)].rgb;
}

// Solid-angle density with which env_sample picks d.
float env_pdf(vec3 d, uvec2 size) {
    float s = sqrt(max(0.0, 1.0 - d.y * d.y));
    return s > 0.0 ? env_texels[env_texel(env_uv(d), size)].w / (2.0 * PI * PI * s) : 0.0;
}

// First index in [lo, lo + count) whose CDF value exceeds u (the last one if none does).
uint env_search_marginal(float u, uint count) {
    uint lo = 0u;
    uint hi = count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (env_marginal[mid] <= u) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

uint env_search_row(float u, uint row, uint width) {
    uint lo = 0u;
    uint hi = width - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (env_conditional[row * width + mid] <= u) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// A direction by the tables (row, then column, then uniformly inside the texel), with its pdf.
vec3 env_sample(vec4 u, uvec2 size, out float pdf) {
    uint y = env_search_marginal(u.x, size.y);
    uint x = env_search_row(u.y, y, size.x);
    vec2 uv = vec2((float(x) + u.z) / float(size.x), (float(y) + u.w) / float(size.y));
    vec3 d = env_direction(uv);
    float s = sin(uv.y * PI);
    pdf = s > 0.0 ? env_texels[y * size.x + x].w / (2.0 * PI * PI * s) : 0.0;
    return d;
}

#endif
