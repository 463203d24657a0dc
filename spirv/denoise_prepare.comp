#version 460
// Denoiser step 1 (src/passes/denoise.rs): a path target's running mean less what the first hit
// emits, divided by the albedo (denoise.glsl), with the variance of the mean of its luminance,
// into `dn_color` (with DENOISE_SPLIT its diffuse part there, its specular part over the specular
// albedo into `dn_specular`); the first hit's unit normal and distance (−1 for a miss) into `dn_guide`, which
// the à-trous steps read; the divisors and the emission into `dn_albedo`, `dn_spec_albedo` and
// `dn_emission`, which the remodulation reads (after the temporal step has accumulated them).
//
// The variance: per channel the unbiased sample variance over the pixel's n samples divided by n,
// (E[x²] − E[x]²)/(n − 1) (the emission's own variance, from the pixel's footprint alone, is left
// in); the channels' standard deviations are summed with the luminance weights (a path's channels
// rise and fall together, so the bound of perfect correlation is closer than independence), and
// the sum squared.
#extension GL_GOOGLE_include_directive : require
#include "kernel/denoise_prepare.glsl"
#include "denoise.glsl"

KERNEL_LOCAL_SIZE;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, params.size))) {
        return;
    }
    uint index = pixel.y * params.size.x + pixel.x;
    vec4 mean = accum[index];
    vec3 square = moment[index].rgb;
    vec3 albedo = denoise_albedo(aov_albedo[index]);
    vec3 emitted = aov_emission[index].rgb;
    float n = max(mean.a, 2.0);
    if ((params.flags & DENOISE_SPLIT) != 0u) {
        // The lobe split: the diffuse and the specular parts, each over its own divisor, each
        // with the variance of its luminance's mean from the path tracer's per-sample squares.
        vec4 specular = aov_specular[index];
        vec4 split = aov_split[index];
        vec3 diffuse = (mean.rgb - emitted - specular.rgb) / albedo;
        float l = dot(DENOISE_LUMA, diffuse);
        imageStore(dn_color, ivec2(pixel), vec4(diffuse, max(specular.a - l * l, 0.0) / (n - 1.0)));
        vec3 spec_albedo = denoise_spec_albedo(aov_albedo[index], split);
        vec3 spec = specular.rgb / spec_albedo;
        l = dot(DENOISE_LUMA, spec);
        imageStore(dn_specular, ivec2(pixel), vec4(spec, max(split.a - l * l, 0.0) / (n - 1.0)));
        imageStore(dn_spec_albedo, ivec2(pixel), vec4(spec_albedo, 0.0));
    } else {
        vec3 sigma = sqrt(max(square - mean.rgb * mean.rgb, vec3(0.0)) / (n - 1.0)) / albedo;
        float sigma_l = dot(DENOISE_LUMA, sigma);
        imageStore(dn_color, ivec2(pixel), vec4((mean.rgb - emitted) / albedo, sigma_l * sigma_l));
    }
    imageStore(dn_samples, ivec2(pixel), vec4(mean.a));
    imageStore(dn_albedo, ivec2(pixel), vec4(albedo, 0.0));
    imageStore(dn_emission, ivec2(pixel), vec4(emitted, 0.0));
    vec4 normal_depth = aov_normal_depth[index];
    bool hit = normal_depth.w < 1e30 && dot(normal_depth.xyz, normal_depth.xyz) > 0.0;
    imageStore(dn_guide, ivec2(pixel), hit ? vec4(normalize(normal_depth.xyz), normal_depth.w) : vec4(0.0, 0.0, 0.0, -1.0));
}
