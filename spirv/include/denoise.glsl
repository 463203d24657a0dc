// What the denoiser's kernels share (src/passes/denoise.rs): the luminance, and the albedo the
// radiance is divided by before filtering and multiplied by after. The including kernel includes
// its `kernel/denoise_*.glsl` first (`params`, the DENOISE_* flags).
#ifndef UMBRA_DENOISE_GLSL
#define UMBRA_DENOISE_GLSL

// Rec. 709 luminance (src/color.rs).
const vec3 DENOISE_LUMA = vec3(0.2126, 0.7152, 0.0722);

// Below this an albedo channel is raised to it: a black surface (an emitter, a dark texel) is
// then divided by 0.01 and multiplied back by the same, so nothing is lost, and the filter's
// luminance weight keeps its amplified radiance apart from its neighbours'.
const float DENOISE_MIN_ALBEDO = 0.01;

// The divisor of a pixel's radiance: its first hit's base colour plus `params.albedo_offset`, or 1
// for a miss (alpha 0) and when demodulation is off.
vec3 denoise_albedo(vec4 albedo) {
    if ((params.flags & DENOISE_DEMODULATE) == 0u || !(albedo.a > 0.0)) {
        return vec3(1.0);
    }
    return max(albedo.rgb + params.albedo_offset, vec3(DENOISE_MIN_ALBEDO));
}

#endif
