#version 460
// Denoiser step 3 (src/passes/denoise.rs): the filtered radiance multiplied back by the albedo
// it was divided by (denoise.glsl), plus what the first hit emits, alpha 1.
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
    imageStore(out_color, ivec2(pixel), vec4(imageLoad(dn_in, ivec2(pixel)).rgb * albedo + emitted, 1.0));
}
