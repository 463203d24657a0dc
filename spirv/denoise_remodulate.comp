#version 460
// Denoiser step 3 (src/passes/denoise.rs): the filtered radiance multiplied back by the albedo
// it was divided by (step 1's `dn_albedo`, accumulated by the temporal step when it ran; with
// DENOISE_SPLIT the specular part's likewise, added), plus what the first hit emits (likewise),
// alpha 1.
#extension GL_GOOGLE_include_directive : require
#include "kernel/denoise_remodulate.glsl"

KERNEL_LOCAL_SIZE;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, params.size))) {
        return;
    }
    vec3 albedo = imageLoad(dn_albedo, ivec2(pixel)).rgb;
    vec3 emitted = imageLoad(dn_emission, ivec2(pixel)).rgb;
    vec3 radiance = imageLoad(dn_in, ivec2(pixel)).rgb * albedo;
    if ((params.flags & DENOISE_SPLIT) != 0u) {
        radiance += imageLoad(dn_specular, ivec2(pixel)).rgb * imageLoad(dn_spec_albedo, ivec2(pixel)).rgb;
    }
    imageStore(out_color, ivec2(pixel), vec4(radiance + emitted, 1.0));
}
