#version 460
// The split-sum BRDF table (ibl.glsl): per entry, a grid of `dst.w` x `dst.w` midpoint samples of
// GGX visible normals (graded towards the distribution's tail) (specular: f cos / pdf = G1(wi),
// split by the Schlick factor) and of the cosine hemisphere (diffuse Fresnel weighting).
#extension GL_GOOGLE_include_directive : require
#include "kernel/ibl_lut.glsl"

KERNEL_LOCAL_SIZE;

#include "ibl.glsl"

void main() {
    uvec2 ij = gl_GlobalInvocationID.xy;
    uint n = IBL_LUT_SIZE;
    if (any(greaterThanEqual(ij, uvec2(n)))) {
        return;
    }
    float nv = (float(ij.x) + 0.5) / float(n);
    // Roughness spans 0..1 edge to edge (roughness 1 is common and steep in A + B); n.v at
    // texel centres (n.v = 0 is degenerate and flat near 1).
    float roughness = float(ij.y) / float(n - 1u);
    float a = max(roughness * roughness, 1e-4);
    vec3 wo = vec3(sqrt(1.0 - nv * nv), 0.0, nv);
    uint m = params.samples;
    vec4 sum = vec4(0.0);
    for (uint sy = 0u; sy < m; ++sy) {
        vec4 row = vec4(0.0);
        for (uint sx = 0u; sx < m; ++sx) {
            vec2 u = (vec2(sx, sy) + 0.5) / float(m);
            // u.x = 1 - (1 - t)^4 (Jacobian 4 (1 - t)^3) puts samples into GGX's long tail
            // (u.x near 1), which an even grid misses at low roughness.
            float s = 1.0 - u.x;
            float s3 = s * s * s;
            vec3 h = sample_ggx_vndf(wo, a, vec2(1.0 - s3 * s, u.y));
            vec3 wi = reflect(-wo, h);
            if (wi.z > 0.0) {
                float fc = ibl_pow5(1.0 - clamp(dot(wo, h), 0.0, 1.0));
                float g = ggx_g1(wi, a) * 4.0 * s3;
                row.x += (1.0 - fc) * g;
                row.y += fc * g;
            }
            vec3 l = sample_cosine_hemisphere(u);
            float fd = ibl_pow5(1.0 - clamp(dot(wo, normalize(wo + l)), 0.0, 1.0));
            row.z += 1.0 - fd;
            row.w += fd;
        }
        sum += row;
    }
    lut[ij.y * n + ij.x] = sum / float(m * m);
}
