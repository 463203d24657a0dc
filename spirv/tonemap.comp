#version 460
// Display transform of a linear image: exposure, a tone curve (src/tonemap.rs is the reference
// twin: clamp, Hill's ACES fit, Khronos PBR Neutral), sRGB encoding, into an 8-bit image.
#extension GL_GOOGLE_include_directive : require
#include "kernel/tonemap.glsl"

KERNEL_LOCAL_SIZE;

vec3 aces_fit(vec3 v) {
    return (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.4329510) + 0.238081);
}

vec3 tone_curve(vec3 c) {
    c = max(mix(c, vec3(0.0), isnan(c)), vec3(0.0));
    if (params.curve == 1u) {
        // GLSL matrices are column-major: these are the rows of src/tonemap.rs, transposed.
        const mat3 aces_in = mat3(0.59719, 0.07600, 0.02840, 0.35458, 0.90834, 0.13383, 0.04823, 0.01566, 0.83777);
        const mat3 aces_out = mat3(1.60475, -0.10208, -0.00327, -0.53108, 1.10813, -0.07276, -0.07367, -0.00605, 1.07602);
        c = aces_out * aces_fit(aces_in * c);
    } else if (params.curve == 2u) {
        const float start = 0.8 - 0.04;
        const float desaturation = 0.15;
        float x = min(c.r, min(c.g, c.b));
        float offset = x < 0.08 ? x - 6.25 * x * x : 0.04;
        c -= offset;
        float peak = max(c.r, max(c.g, c.b));
        if (peak >= start) {
            float d = 1.0 - start;
            float new_peak = 1.0 - d * d / (peak + d - start);
            float g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0);
            c = mix(c * (new_peak / peak), vec3(new_peak), g);
        }
    }
    return clamp(c, 0.0, 1.0);
}

vec3 srgb_encode(vec3 c) {
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(pixel), params.size))) {
        return;
    }
    vec4 c = imageLoad(src, pixel);
    float alpha = isnan(c.a) ? 0.0 : clamp(c.a, 0.0, 1.0);
    imageStore(dst, pixel, vec4(srgb_encode(tone_curve(c.rgb * params.exposure)), alpha));
}
