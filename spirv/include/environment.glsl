// Equirectangular environment lookup and importance sampling (src/environment.rs builds the
// tables). +Y is up; u = atan2(d.x, -d.z) / 2pi + 1/2, v = acos(d.y) / pi, row 0 at the top.
//
// The including kernel declares (the scene's bindings, src/gpu/interface.rs), before including
// this file:
//   layout(rgba32ui) uniform readonly uimageBuffer env_texels; // rgb radiance, density over (u, v)
//   layout(rg32ui) uniform readonly uimageBuffer env_alias;    // alias tables: rows', each row's
// and passes the map's size. Texel buffers, not storage buffers: on llvmpipe a texel read is one
// gather, a storage-buffer read a loop over the lanes (docs/history/2026-12-04.md, fourth
// session).
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

// Texel i: rgb radiance, density over (u, v).
vec4 env_value(uint i) {
    return uintBitsToFloat(imageLoad(env_texels, int(i)));
}

// Radiance arriving along -d (looking towards d).
vec3 env_radiance(vec3 d, uvec2 size) {
    return env_value(env_texel(env_uv(d), size)).rgb;
}

// Solid-angle density of a texel's density over (u, v) at polar angle with sine s.
float env_solid_angle_pdf(float pdf_uv, float s) {
    return s > 0.0 ? pdf_uv / (2.0 * PI * PI * s) : 0.0;
}

// Solid-angle density with which env_sample picks d, given the density over (u, v) of d's texel.
float env_direction_pdf(float pdf_uv, vec3 d) {
    return env_solid_angle_pdf(pdf_uv, sqrt(max(0.0, 1.0 - d.y * d.y)));
}

// Solid-angle density with which env_sample picks d.
float env_pdf(vec3 d, uvec2 size) {
    return env_direction_pdf(env_value(env_texel(env_uv(d), size)).w, d);
}

// One of `count` entries of the alias table starting at entry `at`: entry floor(u.x count) or its
// alias, as u.y falls below its keep probability or not; `scaled` = u.x count, whose fraction is
// uniform and independent of the entry (the caller's jitter within it).
uint env_alias_pick(float scaled, float u, uint at, uint count) {
    uint i = min(uint(scaled), count - 1u);
    uvec2 e = imageLoad(env_alias, int(at + i)).xy;
    return u < uintBitsToFloat(e.x) ? i : e.y;
}

// A direction by the tables (a row, then a texel in it, then a point in the texel uniformly),
// with its solid-angle pdf and the texel's radiance. Each alias pick takes one uniform for the
// entry and one for the keep test; the entry's uniform, scaled, leaves a fraction for the point
// in the texel (its 24 bits less the table's: at least 11 bits with 8192 texels a row).
vec3 env_sample(vec4 u, uvec2 size, out float pdf, out vec3 radiance) {
    float sy = u.x * float(size.y);
    float sx = u.z * float(size.x);
    uint y = env_alias_pick(sy, u.y, 0u, size.y);
    uint x = env_alias_pick(sx, u.w, size.y + y * size.x, size.x);
    vec2 uv = vec2((float(x) + fract(sx)) / float(size.x), (float(y) + fract(sy)) / float(size.y));
    vec4 texel = env_value(y * size.x + x);
    radiance = texel.rgb;
    pdf = env_solid_angle_pdf(texel.w, sin(uv.y * PI));
    return env_direction(uv);
}

#endif
