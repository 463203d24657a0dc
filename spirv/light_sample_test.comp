#version 460
// Test-only: samples the environment map and the emissive triangles with the renderer's own
// environment.glsl and shading.glsl, and evaluates the pdfs the path tracer weighs those samples
// with, for the chi-square tests in tests/sampling/. Modes (`mode`):
//   0 env_sample                      -> (direction, pdf)
//   1 env_pdf at directions[i]        -> (direction, pdf)
//   2 pick_light                      -> (entry, its pmf, its triangle, 0)
//   3 sample_triangle                 -> (b1, b2, 0, 0)
//   4 sample_emissive from the point  -> (world direction, pdf; 0 when it fails)
//   5 the MIS light pdf pathtrace.comp gives a BSDF ray from the point along directions[i]
//     -> (direction, pdf; 0 when the ray hits nothing that emits towards the point)
//   6 mode 4 with sample reuse (SAMPLE_REUSE: the triangle picked by u.y, stretched back)
// Variants 1 and 2 (`variant`) make modes 1 and 5 report a deliberately wrong pdf (2: mode 5 only).
#extension GL_GOOGLE_include_directive : require
#include "kernel/light_sample_test.glsl"

KERNEL_LOCAL_SIZE;

const bool BECKMANN = false;
const bool GGX_WALTER = false;
#define SAMPLE_REUSE (params.mode == 6u)
#define EMITTER_SOLID_ANGLE SOLID_ANGLE_EMITTERS

#include "random.glsl"
#include "environment.glsl"
#include "shading.glsl"

// What pathtrace.comp weighs emission found by a BSDF ray with: the light pdf of the triangle hit
// (the same hit handling and the same emissive_pdf).
float mis_light_pdf(vec3 p, vec3 n, vec3 dir) {
    vec3 origin = offset_ray(p, n);
    Hit hit;
    if (!bvh_closest(origin, dir, 0.0, BVH_INF, hit)) {
        return 0.0;
    }
    uint tri = hit.tri;
    vec3 ng = tri_normal(tri);
    float area = 0.5 * length(ng);
    ng = normalize(ng);
    vec3 wo = -dir;
    if (!any(greaterThan(emitted(tri, hit.bary, ng, wo), vec3(0.0)))) {
        return 0.0;
    }
    float light_pdf = emissive_pdf(tri, area, origin, hit.t, ng, wo);
    // The wrong variants: 1 forgets the cosine at the light (an area density scaled by
    // distance²), 2 gives the area-sampling density wherever the light is sampled by solid angle.
    if (params.variant == 2u) {
        return tri_light_pmf(tri) / area * hit.t * hit.t / abs(dot(ng, wo));
    }
    return params.variant == 1u ? light_pdf * abs(dot(ng, wo)) : light_pdf;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) {
        return;
    }
    uvec2 size = params.env_size;
    uint mode = params.mode;
    vec4 u = rand4(uvec2(i, 0u), 0u, 0u, params.seed);
    if (mode == 0u) {
        float pdf;
        vec3 radiance;
        vec3 d = env_sample(u, size, pdf, radiance);
        results[i] = vec4(d, pdf);
    } else if (mode == 1u) {
        vec3 d = directions[i].xyz;
        float pdf = env_pdf(d, size);
        // The wrong variant forgets the 1 / sin(theta) of the (u, v) -> sphere Jacobian.
        if (params.variant == 1u) {
            pdf *= sqrt(max(0.0, 1.0 - d.y * d.y));
        }
        results[i] = vec4(d, pdf);
    } else if (mode == 2u) {
        uint k = pick_light(u.x, params.light_count);
        results[i] = vec4(float(k), light_cdf_pmf_area(k).y, float(light_tri(k)), 0.0);
    } else if (mode == 3u) {
        results[i] = vec4(sample_triangle(u.xy), 0.0, 0.0);
    } else if (mode == 4u || mode == 6u) {
        vec3 p = params.point;
        vec3 n = params.normal;
        vec3 t;
        vec3 b;
        basis(n, t, b);
        vec3 wi_local;
        vec3 l_emit;
        float light_pdf;
        if (sample_emissive(p, n, t, b, n, false, u.xyz, params.light_count, wi_local, l_emit, light_pdf)) {
            results[i] = vec4(wi_local.x * t + wi_local.y * b + wi_local.z * n, light_pdf);
        } else {
            results[i] = vec4(0.0);
        }
    } else {
        vec3 d = directions[i].xyz;
        results[i] = vec4(d, mis_light_pdf(params.point, params.normal, d));
    }
}
