#version 460
// Progressive path tracer: a run of samples per pixel per dispatch (path regeneration, main()),
// accumulated as a running mean with its second moment. Next-event estimation on emissive
// triangles, BSDF sampling, multiple importance sampling (power or balance heuristic), Russian
// roulette; or, for comparison, either strategy alone (LIGHT_SAMPLING, BSDF_HITS). Materials'
// occlusion maps (glTF occlusionTexture) are not read: the paths trace the occlusion they stand
// in for (the hybrid renderer applies them to its image-based light).
#extension GL_GOOGLE_include_directive : require
#include "kernel/pathtrace.glsl"
#include "pixel.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

#include "random.glsl"
#include "camera.glsl"
#include "environment.glsl"
#include "shading.glsl"

#include "path.glsl"

// A light sample's shadow ray, traced at once.
void path_shadow(inout Path path, vec3 origin, vec3 d, float tmax, vec3 c, uint bit) {
    if (!bvh_any(origin, d, 0.0, tmax)) {
        path.radiance += c;
        path.nonfinite |= nonfinite_bit(c, bit);
    }
}

// Traces `path`'s ray and shades what it finds (path_shade). False when the path ends there.
bool path_step(inout Path path, uvec2 pixel, uint sample_index, inout vec4 albedo, inout vec4 normal_depth,
               inout vec3 emitted_first) {
    Hit hit;
    bool found = bvh_closest(path.origin, path.dir, 0.0, BVH_INF, hit);
    return path_shade(path, found, hit, pixel, sample_index, albedo, normal_depth, emitted_first);
}

// Sample `sample_index` of `pixel` (of the whole image): its camera ray.
Path camera_path_of(uvec2 pixel, uint sample_index) {
    return camera_path(params.camera.origin, params.camera.forward, params.camera.right, params.camera.up,
                       uvec2(params.camera.image_width, params.camera.image_height), pixel, sample_index);
}

// Samples params.sample_index .. + params.sample_count of one pixel of the region (its random
// numbers and camera ray those of the whole image's pixel). A SIMD machine runs a group
// of lanes until its last lane is done, and path lengths differ (escapes, Russian roulette), so
// a lane whose path ends starts its pixel's next sample in the same iteration (path
// regeneration, Novák, Havran and Dachsbacher 2010) instead of idling until the longest path of
// its group ends: the group then idles once per dispatch, not once per sample. Sample k draws the
// numbers of sample k whichever dispatch and lane trace it, so the paths are those of one sample
// per dispatch.
// Returns the path segments it traced.
uint trace_pixel(uvec2 region_pixel) {
    uint index = region_pixel.y * params.size.x + region_pixel.x;
    uvec2 pixel = region_pixel + uvec2(params.camera.region_x, params.camera.region_y);
    uint first = params.sample_index;
    uint count = params.sample_count;
    // The samples accumulated so far (0: the host cleared the buffers to start a render).
    vec4 mean = accum[index];
    bool fresh = mean.a == 0.0;

    // Per sample: the first hit's base colour (the environment's colour, alpha 0, for a miss),
    // normal and distance, and what it emits; summed over the samples but for the normal and
    // distance, kept from the first sample of the render.
    vec4 albedo = vec4(params.env, 0.0);
    vec4 normal_depth = vec4(0.0, 0.0, 0.0, BVH_INF);
    vec3 emitted_first = vec3(0.0);
    vec4 first_normal_depth = normal_depth;
    vec4 sum_albedo = vec4(0.0);
    vec3 sum_emitted = vec3(0.0);
    vec3 sum = vec3(0.0);   // of the finite samples
    vec3 sum2 = vec3(0.0);  // of their squares
    uint j = 0u;
    uint segments = 0u;
    Path path = camera_path_of(pixel, first);
    while (true) {
        ++segments;
        if (path_step(path, pixel, first + j, albedo, normal_depth, emitted_first)) {
            continue;
        }
        vec3 radiance = path.radiance;
        if (any(isnan(radiance)) || any(isinf(radiance))) {
            atomicAdd(stats.nonfinite_samples, 1u);
            atomicOr(stats.nonfinite_sources, path.nonfinite);
            radiance = vec3(0.0);
            emitted_first = vec3(0.0);
        }
        sum += radiance;
        sum2 += radiance * radiance;
        sum_albedo += albedo;
        sum_emitted += emitted_first;
        if (j == 0u) {
            first_normal_depth = normal_depth;
        }
        ++j;
        if (j >= count) {
            break;
        }
        path = camera_path_of(pixel, first + j);
        albedo = vec4(params.env, 0.0);
        normal_depth = vec4(0.0, 0.0, 0.0, BVH_INF);
        emitted_first = vec3(0.0);
    }

    // The running mean and mean square over all samples so far.
    float n_samples = mean.a + float(count);
    vec4 m2 = moment[index];
    accum[index] = vec4(mean.rgb + (sum - float(count) * mean.rgb) / n_samples, n_samples);
    moment[index] = vec4(m2.rgb + (sum2 - float(count) * m2.rgb) / n_samples, 0.0);
    vec4 mean_albedo = fresh ? vec4(0.0) : aov_albedo[index];
    aov_albedo[index] = mean_albedo + (sum_albedo - float(count) * mean_albedo) / n_samples;
    vec3 mean_emitted = fresh ? vec3(0.0) : aov_emission[index].rgb;
    aov_emission[index] = vec4(mean_emitted + (sum_emitted - float(count) * mean_emitted) / n_samples, 0.0);
    if (fresh) {
        aov_normal_depth[index] = first_normal_depth;
    }
    return segments;
}

shared uint group_segments;

void main() {
    if (gl_LocalInvocationIndex == 0u) {
        group_segments = 0u;
    }
    barrier();
    uvec2 pixel = tile_pixel();
    if (all(lessThan(pixel, params.size))) {
        atomicAdd(group_segments, trace_pixel(pixel));
        if (HAS_IMPLICIT) {
            if (implicit_marches_exhausted > 0u) {
                atomicAdd(stats.marches_exhausted, implicit_marches_exhausted);
            }
        }
    }
    // One global atomic per workgroup: the segment count, 64 bits as two words (an add that
    // wraps the low word carries one into the high word).
    barrier();
    if (gl_LocalInvocationIndex == 0u) {
        uint n = group_segments;
        uint old = atomicAdd(stats.segments_lo, n);
        if (old + n < old) {
            atomicAdd(stats.segments_hi, 1u);
        }
    }
}
