#version 460
// Denoiser step 3 (src/passes/denoise.rs): the filtered radiance multiplied back by the albedo
// it was divided by (denoise.glsl; with DENOISE_SPLIT the specular part's likewise, added), plus
// what the first hit emits, alpha 1.
#extension GL_GOOGLE_include_directive : require
#include "kernel/denoise_remodulate.glsl"
#include "denoise.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, params.size))) {
        return;
    }
    uint index = pixel.y * params.size.x + pixel.x;
    vec3 albedo = denoise_albedo(aov_albedo[index]);
    vec3 emitted = aov_emission[index].rgb;
    vec3 radiance = imageLoad(dn_in, ivec2(pixel)).rgb * albedo;
    if ((params.flags & DENOISE_SPLIT) != 0u) {
        vec3 spec_albedo = denoise_spec_albedo(aov_albedo[index], aov_split[index]);
        radiance += imageLoad(dn_specular, ivec2(pixel)).rgb * spec_albedo;
    }
    imageStore(out_color, ivec2(pixel), vec4(radiance + emitted, 1.0));
}
