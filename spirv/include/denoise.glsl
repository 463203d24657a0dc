// What the denoiser's kernels share (src/passes/denoise.rs): the luminance, and the albedo the
// radiance is divided by before filtering and multiplied by after. The including kernel includes
// its `kernel/denoise_*.glsl` first (`params`, the DENOISE_* flags).
#ifndef UMBRA_DENOISE_GLSL
#define UMBRA_DENOISE_GLSL

// Rec. 709 luminance (src/color.rs).
const vec3 DENOISE_LUMA = vec3(0.2126, 0.7152, 0.0722);

// The divisor of a pixel's radiance (with DENOISE_SPLIT, of its diffuse part): its first hit's
// base colour plus `params.albedo_offset`, raised to DENOISE_MIN_ALBEDO (a black surface, an
// emitter or a dark texel, is then divided by 0.01 and multiplied back by the same, so nothing is
// lost, and the filter's luminance weight keeps its amplified radiance apart from its
// neighbours'), or 1 for a miss (alpha 0) and when demodulation is off.
vec3 denoise_albedo(vec4 albedo) {
    if ((params.flags & DENOISE_DEMODULATE) == 0u || !(albedo.a > 0.0)) {
        return vec3(1.0);
    }
    return max(albedo.rgb + params.albedo_offset, vec3(DENOISE_MIN_ALBEDO));
}

// With DENOISE_SPLIT, the divisor of a pixel's specular part: the mean of its first hits'
// specular albedos (`split`: the path target's aov_split), or 1 where its base colour's is.
vec3 denoise_spec_albedo(vec4 albedo, vec4 split) {
    if ((params.flags & DENOISE_DEMODULATE) == 0u || !(albedo.a > 0.0)) {
        return vec3(1.0);
    }
    return max(split.rgb, vec3(DENOISE_MIN_ALBEDO));
}

#endif
