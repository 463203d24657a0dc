#version 460
// Progressive path tracer: a run of samples per pixel per dispatch (path regeneration, main()),
// accumulated as a running mean with its second moment. Next-event estimation on emissive
// triangles, BSDF sampling, multiple importance sampling (power or balance heuristic), Russian
// roulette; or, for comparison, either strategy alone (LIGHT_SAMPLING, BSDF_HITS). Materials'
// occlusion maps (glTF occlusionTexture) are not read: the paths trace the occlusion they stand
// in for (the hybrid renderer applies them to its image-based light).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "kernel/pathtrace.glsl"
#include "pixel.glsl"

KERNEL_LOCAL_SIZE;

// COUNT_LANES (a diagnostic: PathTarget::with_lane_counts): how busy the SIMD lanes are in the
// BVH walks. Every walk-loop iteration counts; per trace, the iterations of the subgroup's
// active lanes are summed and their largest (what the group ran: a loop runs until its slowest
// lane is done) counted once, closest-hit and any-hit traces apart (x, y and z, w), into
// PathStats at the end.
uint walk_iterations = 0u;
uvec4 lane_counts = uvec4(0u);
#define BVH_ITERATION    \
    if (COUNT_LANES) {   \
        ++walk_iterations; \
    }

// Counts a trace whose walks began at `walk_iterations` = `before` (any_hit: a shadow ray's).
void count_trace(uint before, bool any_hit) {
    if (COUNT_LANES) {
        uint lanes = subgroupAdd(walk_iterations - before);
        uint group = subgroupMax(walk_iterations - before);
        // One lane of the active ones (subgroupElect, which naga's SPIR-V reader lacks).
        if (gl_SubgroupInvocationID == subgroupBroadcastFirst(gl_SubgroupInvocationID)) {
            lane_counts += any_hit ? uvec4(0u, 0u, lanes, group) : uvec4(lanes, group, 0u, 0u);
        }
    }
}

// Low-discrepancy numbers take sample reuse: a choice and the chosen option's sample from one
// number (bsdf.glsl).
#define SAMPLE_REUSE LOW_DISCREPANCY
#define EMITTER_SOLID_ANGLE SOLID_ANGLE_EMITTERS
#include "random.glsl"
#include "camera.glsl"
#include "environment.glsl"
#include "shading.glsl"
#include "ris_reuse.glsl"

#include "path.glsl"

// A light sample's shadow ray, traced at once.
void path_shadow(inout Path path, vec3 origin, vec3 d, float tmax, vec3 c, vec3 c_spec, uint bit) {
    uint before = walk_iterations;
    bool blocked = bvh_any(origin, d, 0.0, tmax);
    count_trace(before, true);
    if (!blocked) {
        path.radiance += c;
        path.specular += c_spec;
        path.nonfinite |= nonfinite_bit(c, bit);
    }
}

// Traces `path`'s ray: its closest hit into `hit`, false where it leaves the scene.
bool path_trace(Path path, out Hit hit) {
    uint before = walk_iterations;
    bool found = bvh_closest(path.origin, path.dir, 0.0, BVH_INF, hit);
    count_trace(before, false);
    return found;
}

// Sample `sample_index` of `pixel` (of the whole image): its camera ray.
Path camera_path_of(uvec2 pixel, uint sample_index) {
    return camera_path(params.camera.origin, params.camera.forward, params.camera.right, params.camera.up,
                       camera_orthographic(params.camera.flags), uvec2(params.camera.image_width, params.camera.image_height), pixel, sample_index);
}

// One pixel's samples of a dispatch: the path in flight and the sums of the finished ones.
struct PixelSamples {
    Path path;
    uint j;  // the path's sample, counted from params.sample_index
    // The sample's first hit: its base colour (the environment's colour, alpha 0, for a miss),
    // normal and distance, and what it emits; summed over the samples but for the normal and
    // distance, kept from the first sample of the render.
    vec4 albedo;
    vec4 normal_depth;
    vec3 emitted_first;
    vec4 first_normal_depth;
    SampleSums sums;
};

// Starts sample ps.j of `pixel`: its camera ray.
void start_sample(inout PixelSamples ps, uvec2 pixel) {
    ps.path = camera_path_of(pixel, params.sample_index + ps.j);
    ps.albedo = vec4(params.env, 0.0);
    ps.normal_depth = vec4(0.0, 0.0, 0.0, BVH_INF);
    ps.emitted_first = vec3(0.0);
}

// Folds the finished path into the sums and starts the pixel's next sample; false when the
// dispatch's samples of the pixel are done.
bool next_sample(inout PixelSamples ps, uvec2 pixel) {
    fold_sample(ps.sums, ps.path.radiance, ps.emitted_first, ps.path.nonfinite, ps.albedo, ps.path.specular,
                ps.path.metallic);
    if (ps.j == 0u) {
        ps.first_normal_depth = ps.normal_depth;
    }
    ++ps.j;
    if (ps.j >= params.sample_count) {
        return false;
    }
    start_sample(ps, pixel);
    return true;
}

// Samples params.sample_index .. + params.sample_count of one pixel of the region (its random
// numbers and camera ray those of the whole image's pixel). A SIMD machine runs a group
// of lanes until its last lane is done, and path lengths differ (escapes, Russian roulette), so
// a lane whose path ends starts its pixel's next sample in the same iteration (path
// regeneration, Novák, Havran and Dachsbacher 2010) instead of idling until the longest path of
// its group ends: the group then idles once per dispatch, not once per sample. Sample k draws the
// numbers of sample k whichever dispatch and lane trace it, so the paths are those of one sample
// per dispatch.
// A ray that leaves the scene ends its path with an environment lookup alone, and its lane can
// trace its pixel's next camera ray before the group shades (the inner loop): the shading, which
// a SIMD CPU (llvmpipe) runs for every lane of the group whichever lanes have a hit, is then
// spent on fewer lanes that have none (in an open scene most segments escape). A walk that only
// the missed lanes need costs the group a walk for fewer rays, so the group walks again only
// while at least half of its lanes still sampling missed; below that, the lanes that missed wait
// through the shading and walk their next rays with the group's next segments. Which lanes walk
// when changes no path.
// Returns the path segments it traced.
uint trace_pixel(uvec2 region_pixel) {
    uint index = region_pixel.y * params.size.x + region_pixel.x;
    uvec2 pixel = region_pixel + uvec2(params.camera.region & 0xffffu, params.camera.region >> 16);

    PixelSamples ps;
    ps.j = 0u;
    ps.first_normal_depth = vec4(0.0, 0.0, 0.0, BVH_INF);
    ps.sums = no_samples();
    uint segments = 0u;
    if (ris_reuses()) {
        // One sample per dispatch (the host's): this index's reservoir, none unless path_ris
        // makes one.
        ris_reuse_clear(index);
    }
    start_sample(ps, pixel);
    // `ended`: the path in flight has ended and waits for next_sample; `found`: it has a hit to
    // shade.
    bool ended = false;
    bool more = true;
    while (true) {
        Hit hit;
        bool found = false;
        bool again;
        do {
            if (more && !found) {
                if (ended) {
                    more = next_sample(ps, pixel);
                }
                if (more) {
                    ++segments;
                    found = path_trace(ps.path, hit);
                    if (!found) {
                        path_shade(ps.path, false, hit, pixel, params.sample_index + ps.j, ps.albedo,
                                   ps.normal_depth, ps.emitted_first);
                    }
                    ended = !found;
                }
            }
            // The group's lanes still sampling without a hit (low half) and with one (high half).
            uint lanes = subgroupAdd(more ? (found ? 0x10000u : 1u) : 0u);
            uint missed = lanes & 0xffffu;
            again = missed > 0u && 2u * missed >= missed + (lanes >> 16);
        } while (again);
        if (!more) {
            break;
        }
        if (found) {
            ended = !path_shade(ps.path, true, hit, pixel, params.sample_index + ps.j, ps.albedo, ps.normal_depth,
                                ps.emitted_first);
        }
    }

    accumulate_sums(index, params.sample_count, ps.sums, ps.first_normal_depth);
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
        count_marches();
    }
    // One global atomic per workgroup: the segment count.
    barrier();
    if (gl_LocalInvocationIndex == 0u) {
        count_segments(group_segments);
    }
    if (COUNT_LANES) {
        if (any(notEqual(lane_counts, uvec4(0u)))) {
            PATH_ADD_COUNT(stats.walk_lanes_closest[0], stats.walk_lanes_closest[1], lane_counts.x);
            PATH_ADD_COUNT(stats.walk_groups_closest[0], stats.walk_groups_closest[1], lane_counts.y);
            PATH_ADD_COUNT(stats.walk_lanes_any[0], stats.walk_lanes_any[1], lane_counts.z);
            PATH_ADD_COUNT(stats.walk_groups_any[0], stats.walk_groups_any[1], lane_counts.w);
        }
    }
}
