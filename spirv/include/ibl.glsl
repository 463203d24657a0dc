// Image-based lighting with the split-sum approximation (src/ibl.rs, src/passes/ibl.rs).
//
// - BRDF LUT: IBL_LUT_SIZE x IBL_LUT_SIZE vec4s over (n.v, perceptual roughness) at
//   ((i + 0.5) / N, j / (N - 1)) (roughness edge to edge: roughness 1 is not clamped), entry j * N + i:
//     x = A, y = B: the specular term's directional albedo = F0 A + F90 B (Schlick split),
//     z = C, w = D: the cosine-weighted average of the diffuse lobe's Fresnel weighting,
//                   1 - max3(F) = 1 - max3(F0) C - F90 D (C + D = 1).
// - Prefiltered environment: IBL_LEVELS equirectangular levels, level k for perceptual roughness
//   k / (IBL_LEVELS - 1). Level 0 is the source map itself (env_texels, the mirror); levels 1.. are
//   stored one after another in one buffer, sizes by ibl_level_size.
// - Box chain (for filtered importance sampling): level 0 is the source, levels 1.. (each half the
//   previous, at least 1x1, solid-angle weighted 2x2 averages) one after another in one buffer.
// - Irradiance: 9 SH coefficients (rgb in xyz) already multiplied by the clamped-cosine
//   convolution factors A_l (pi, 2pi/3, pi/4), so E(n) = sum c_lm Y_lm(n).
#ifndef UMBRA_IBL_GLSL
#define UMBRA_IBL_GLSL

#include "sampling.glsl"

const uint IBL_LEVELS = 6u;
const uint IBL_LUT_SIZE = 32u;
// Prefiltered level 1 is at most IBL_MAX_WIDTH / 2 wide (the source is halved until it fits).
const uint IBL_MAX_WIDTH = 1024u;

float ibl_pow5(float x) {
    float x2 = x * x;
    return x2 * x2 * x;
}

// Van der Corput / Hammersley point i of n.
vec2 hammersley(uint i, uint n) {
    return vec2((float(i) + 0.5) / float(n), float(bitfieldReverse(i)) * 2.3283064365386963e-10);
}

// Size of prefiltered level k >= 1 for a source of `src`.
uvec2 ibl_level_size(uint k, uvec2 src) {
    uvec2 s = src;
    while (s.x > IBL_MAX_WIDTH) {
        s = max(s >> 1u, uvec2(1u));
    }
    return max(s >> k, uvec2(8u, 4u));
}

// First texel of prefiltered level k >= 1 in the prefiltered buffer.
uint ibl_level_offset(uint k, uvec2 src) {
    uint o = 0u;
    for (uint i = 1u; i < k; ++i) {
        uvec2 s = ibl_level_size(i, src);
        o += s.x * s.y;
    }
    return o;
}

uvec2 chain_size(uint k, uvec2 src) {
    return max(src >> k, uvec2(1u));
}

// Levels of the box chain, the source included: down to 1x1.
uint chain_levels(uvec2 src) {
    return uint(findMSB(max(src.x, src.y))) + 1u;
}

// First texel of chain level k >= 1 in the chain buffer.
uint chain_offset(uint k, uvec2 src) {
    uint o = 0u;
    for (uint i = 1u; i < k; ++i) {
        uvec2 s = chain_size(i, src);
        o += s.x * s.y;
    }
    return o;
}

// Bilinear taps of texel-centre coordinates `uv * size - 0.5` in an equirectangular level:
// u wraps, v clamps. Indices into the level (row-major), weights summing to 1.
void equirect_taps(vec2 uv, uvec2 size, out uvec4 idx, out vec4 w) {
    vec2 p = uv * vec2(size) - 0.5;
    vec2 f = fract(p);
    ivec2 i0 = ivec2(floor(p));
    int w_ = int(size.x);
    int h_ = int(size.y);
    int x0 = (i0.x % w_ + w_) % w_;
    int x1 = (x0 + 1) % w_;
    int y0 = clamp(i0.y, 0, h_ - 1);
    int y1 = clamp(i0.y + 1, 0, h_ - 1);
    idx = uvec4(y0 * w_ + x0, y0 * w_ + x1, y1 * w_ + x0, y1 * w_ + x1);
    w = vec4((1.0 - f.x) * (1.0 - f.y), f.x * (1.0 - f.y), (1.0 - f.x) * f.y, f.x * f.y);
}

// Real SH basis, bands 0..2, at unit d.
void sh9_basis(vec3 d, out float y[9]) {
    y[0] = 0.282094792;
    y[1] = 0.488602512 * d.y;
    y[2] = 0.488602512 * d.z;
    y[3] = 0.488602512 * d.x;
    y[4] = 1.092548431 * d.x * d.y;
    y[5] = 1.092548431 * d.y * d.z;
    y[6] = 0.315391565 * (3.0 * d.z * d.z - 1.0);
    y[7] = 1.092548431 * d.x * d.z;
    y[8] = 0.546274215 * (d.x * d.x - d.y * d.y);
}

// The SH basis integrated exactly over the lat-long cell [theta0, theta1] x [phi0, phi1]
// (direction (sin t sin p, cos t, -sin t cos p) as env_direction), so a piecewise-constant map
// projects exactly (a constant map has no band 1 or 2).
void sh9_cell(float t0, float t1, float p0, float p1, out float y[9]) {
    float dp = p1 - p0;
    float ps = cos(p0) - cos(p1);
    float pc = sin(p1) - sin(p0);
    float s2 = 0.25 * (sin(2.0 * p1) - sin(2.0 * p0));
    float pss = 0.5 * dp - s2;
    float pcc = 0.5 * dp + s2;
    float psc = 0.5 * (sin(p1) * sin(p1) - sin(p0) * sin(p0));
    float c0 = cos(t0), c1 = cos(t1), n0 = sin(t0), n1 = sin(t1);
    float t1_ = c0 - c1;
    float ts = 0.5 * (t1 - t0) - 0.25 * (sin(2.0 * t1) - sin(2.0 * t0));
    float tc = 0.5 * (n1 * n1 - n0 * n0);
    float tss = (c0 - c0 * c0 * c0 / 3.0) - (c1 - c1 * c1 * c1 / 3.0);
    float tcc = (c0 * c0 * c0 - c1 * c1 * c1) / 3.0;
    float tsc = (n1 * n1 * n1 - n0 * n0 * n0) / 3.0;
    y[0] = 0.282094792 * t1_ * dp;
    y[1] = 0.488602512 * tc * dp;
    y[2] = -0.488602512 * ts * pc;
    y[3] = 0.488602512 * ts * ps;
    y[4] = 1.092548431 * tsc * ps;
    y[5] = -1.092548431 * tsc * pc;
    y[6] = 0.315391565 * (3.0 * tss * pcc - t1_ * dp);
    y[7] = -1.092548431 * tss * psc;
    y[8] = 0.546274215 * (tss * pss - tcc * dp);
}

// Clamped-cosine convolution factors A_l of band l (Ramamoorthi and Hanrahan 2001).
float sh9_band_factor(uint i) {
    return i == 0u ? PI : (i < 4u ? 2.0 * PI / 3.0 : 0.25 * PI);
}

#endif
