#version 460
// The wavefront path tracer (Laine, Karras and Aila 2013, "Megakernels considered harmful"): the
// megakernel's paths (pathtrace.comp, the same path_shade of path.glsl and the same random
// numbers, so the same samples) with each step of a path a kernel of its own, run over a queue
// of the paths that take it. A wave traces `sample_count` samples of every pixel of the region:
//   camera rays  every path's state from its camera ray; all of them in round 0's ray queue;
//   then per round r = 0 .. max_bounces:
//   extend       the closest hit of each queued path's ray;
//   shade        path_shade at it: emission, light samples (their shadow rays queued with the
//                contribution each brings if unblocked), the next ray (the path queued for round
//                r + 1) or the path's end;
//   connect      each path's queued shadow rays, in the order they were made, adding what reaches;
//   accumulate   every pixel's samples of the wave into the running mean, as pathtrace.comp
//                (and with SPLIT_LOBES, the denoiser's lobe split, into aov_specular and aov_split).
// Each stage is this kernel specialised with one of the WF_* constants; the host dispatches the
// queue stages indirectly from the queues' counts (wf_counts), so a stage runs as many lanes as
// paths take it: a SIMD group no longer runs the union of its lanes' branches of a path step
// (misses, emitters, light kinds, materials), and a trace kernel holds no shading state. What it
// costs instead: each path's state written and read through memory at every stage.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "kernel/wavefront.glsl"
#include "pixel.glsl"

KERNEL_LOCAL_SIZE;

// Low-discrepancy numbers take sample reuse: a choice and the chosen option's sample from one
// number (bsdf.glsl).
#define SAMPLE_REUSE LOW_DISCREPANCY
#define EMITTER_SOLID_ANGLE SOLID_ANGLE_EMITTERS
#include "random.glsl"
#include "camera.glsl"
#include "environment.glsl"
#include "shading.glsl"

// Fields of a path's state (WAVE_FIELDS of them, `capacity` texels each).
const uint F_ORIGIN = 0u;      // origin xyz, prev_pdf
const uint F_DIR = 1u;         // direction xyz, depth | the dispersion channel << 16
const uint F_THROUGHPUT = 2u;  // throughput rgb, shadow rays queued this round
const uint F_RADIANCE = 3u;    // radiance rgb, non-finite sources
const uint F_ALBEDO = 4u;      // the first hit's base colour (alpha 0: a miss)
const uint F_NORMAL = 5u;      // the first hit's normal and distance
const uint F_EMITTED = 6u;     // the first hit's emission rgb
const uint F_HIT = 7u;         // this round's closest hit: t, triangle (WAVE_MISS), barycentrics
// SPLIT_LOBES only (WAVE_SPLIT_FIELDS more: Path's fields for the lobe split):
const uint F_SPECULAR = 8u;    // the radiance's specular part rgb
const uint F_SPLIT = 9u;       // the specular share beyond the first hit rgb, the first hit's metallic

// The fields of a path's state, and the texels of a queued shadow ray: texel 3 (SPLIT_LOBES
// only) its contribution's specular part.
uint path_fields() {
    if (SPLIT_LOBES) {
        return WAVE_FIELDS + WAVE_SPLIT_FIELDS;
    }
    return WAVE_FIELDS;
}

uint shadow_ray_texels() {
    if (SPLIT_LOBES) {
        return WAVE_SHADOW_TEXELS + WAVE_SPLIT_SHADOW_TEXELS;
    }
    return WAVE_SHADOW_TEXELS;
}

uvec4 load_field(uint field, uint path) {
    return imageLoad(wf_paths, int(field * params.capacity + path));
}

vec4 load_fieldf(uint field, uint path) {
    return uintBitsToFloat(load_field(field, path));
}

void store_field(uint field, uint path, uvec4 v) {
    imageStore(wf_paths, int(field * params.capacity + path), v);
}

void store_fieldf(uint field, uint path, vec4 v) {
    store_field(field, path, floatBitsToUint(v));
}

// Shadow ray k of path `path`: its first texel.
int shadow_texel(uint path, uint k) {
    return int(path_fields() * params.capacity + (path * params.shadows_per_path + k) * shadow_ray_texels());
}

// The queues' headers in wf_counts: round r's ray queue and shadow queue.
uint ray_header(uint round) {
    return 4u * round;
}

uint shadow_header(uint round) {
    return 4u * (params.max_bounces + 2u + round);
}

// Appends `path` to the queue of `header` whose entries start at `base`, with the other lanes
// of the subgroup that append to it here: one atomic add per subgroup (a lane's entry is its rank
// among them), and the workgroups of the indirect dispatch grown to cover the entries (the
// subgroups' intervals tile the queue, so their growths add up to ceil(entries / 64)).
void queue_append(uint header, uint base, uint path) {
    uint rank = subgroupExclusiveAdd(1u);
    uint n = subgroupAdd(1u);
    uint first = 0u;
    if (gl_SubgroupInvocationID == subgroupBroadcastFirst(gl_SubgroupInvocationID)) {
        first = atomicAdd(wf_counts[header + 3u], n);
        uint groups = (first + n + 63u) / 64u - (first + 63u) / 64u;
        if (groups > 0u) {
            atomicAdd(wf_counts[header], groups);
        }
    }
    first = subgroupBroadcastFirst(first);
    imageStore(wf_queue, int(base + first + rank), uvec4(path));
}

// The queue entry this invocation of an indirect dispatch takes (false past the queue's end).
bool queue_entry(uint header, uint base, out uint path) {
    uint index = gl_WorkGroupID.x * 64u + gl_LocalInvocationIndex;
    path = 0u;
    if (index >= wf_counts[header + 3u]) {
        return false;
    }
    path = imageLoad(wf_queue, int(base + index)).x;
    return true;
}

// The pixel (of the whole image) and sample index of path `path`: sample `path / pixels` of the
// wave at region pixel `path % pixels`.
void path_pixel(uint path, out uvec2 pixel, out uint sample_index) {
    uint pixels = params.size.x * params.size.y;
    uint p = path % pixels;
    pixel = uvec2(p % params.size.x, p / params.size.x) + uvec2(wf_camera.region & 0xffffu, wf_camera.region >> 16);
    sample_index = params.sample_index + path / pixels;
}

// The shadow rays path_shade makes in this invocation (shade): how many so far, for whose path.
uint shade_path = 0u;
uint shade_shadows = 0u;

// path.glsl's RIS at the first hit is the megakernel's alone (src/passes/wavefront.rs refuses it).
const bool RIS = false;

#include "path.glsl"

// A light sample's shadow ray, queued: the connect stage traces it.
void path_shadow(inout Path path, vec3 origin, vec3 d, float tmax, vec3 c, vec3 c_spec, uint bit) {
    int texel = shadow_texel(shade_path, shade_shadows);
    imageStore(wf_paths, texel, floatBitsToUint(vec4(origin, tmax)));
    imageStore(wf_paths, texel + 1, floatBitsToUint(vec4(d, 0.0)));
    imageStore(wf_paths, texel + 2, uvec4(floatBitsToUint(c), bit));
    if (SPLIT_LOBES) {
        imageStore(wf_paths, texel + 3, uvec4(floatBitsToUint(c_spec), 0u));
    }
    ++shade_shadows;
}

// Camera rays: path j * pixels + p is sample j of the wave at region pixel p.
void camera_rays() {
    uvec2 region_pixel = tile_pixel();
    if (any(greaterThanEqual(region_pixel, params.size))) {
        return;
    }
    uint path = gl_WorkGroupID.z * params.size.x * params.size.y + region_pixel.y * params.size.x + region_pixel.x;
    uvec2 pixel;
    uint sample_index;
    path_pixel(path, pixel, sample_index);
    Path p = camera_path(wf_camera.origin, wf_camera.forward, wf_camera.right, wf_camera.up,
                         camera_orthographic(wf_camera.flags), uvec2(wf_camera.image_width, wf_camera.image_height), pixel, sample_index);
    store_fieldf(F_ORIGIN, path, vec4(p.origin, p.prev_pdf));
    store_field(F_DIR, path, uvec4(floatBitsToUint(p.dir), p.depth | p.channel << 16u));
    store_fieldf(F_THROUGHPUT, path, vec4(p.throughput, 0.0));
    store_field(F_RADIANCE, path, uvec4(floatBitsToUint(p.radiance), p.nonfinite));
    if (SPLIT_LOBES) {
        store_fieldf(F_SPECULAR, path, vec4(p.specular, 0.0));
        store_fieldf(F_SPLIT, path, vec4(p.share, p.metallic));
    }
    queue_append(ray_header(0u), 0u, path);
}

// Extend: the closest hit of each queued path's ray. Counts the segments, one 64-bit add per
// workgroup as pathtrace.comp.
void extend() {
    uint base = (params.round & 1u) * params.capacity;
    uint path;
    if (queue_entry(ray_header(params.round), base, path)) {
        vec3 origin = load_fieldf(F_ORIGIN, path).xyz;
        vec3 dir = load_fieldf(F_DIR, path).xyz;
        Hit hit;
        if (bvh_closest(origin, dir, 0.0, BVH_INF, hit)) {
            store_field(F_HIT, path, uvec4(floatBitsToUint(hit.t), hit.tri, floatBitsToUint(hit.bary)));
        } else {
            store_field(F_HIT, path, uvec4(0u, WAVE_MISS, 0u, 0u));
        }
        count_marches();
    }
    if (gl_LocalInvocationIndex == 0u) {
        uint count = wf_counts[ray_header(params.round) + 3u];
        uint first = gl_WorkGroupID.x * 64u;
        count_segments(min(count - min(count, first), 64u));
    }
}

// Shade: path_shade at each queued path's hit; its shadow rays queued for connect, the path
// queued for the next round's extend if it goes on.
void shade() {
    uint path;
    if (!queue_entry(ray_header(params.round), (params.round & 1u) * params.capacity, path)) {
        return;
    }
    uvec2 pixel;
    uint sample_index;
    path_pixel(path, pixel, sample_index);
    vec4 o = load_fieldf(F_ORIGIN, path);
    uvec4 d = load_field(F_DIR, path);
    vec4 tp = load_fieldf(F_THROUGHPUT, path);
    uvec4 r = load_field(F_RADIANCE, path);
    uvec4 h = load_field(F_HIT, path);
    Path p;
    p.origin = o.xyz;
    p.prev_pdf = o.w;
    p.dir = uintBitsToFloat(d.xyz);
    p.depth = d.w & 0xffffu;
    p.channel = d.w >> 16u;
    p.throughput = tp.rgb;
    p.radiance = uintBitsToFloat(r.rgb);
    p.nonfinite = r.w;
    if (SPLIT_LOBES) {
        p.specular = load_fieldf(F_SPECULAR, path).rgb;
        vec4 split = load_fieldf(F_SPLIT, path);
        p.share = split.rgb;
        p.metallic = split.w;
    }
    Hit hit;
    hit.t = uintBitsToFloat(h.x);
    hit.tri = h.y;
    hit.bary = uintBitsToFloat(h.zw);
    vec4 albedo = vec4(params.env, 0.0);
    vec4 normal_depth = vec4(0.0, 0.0, 0.0, BVH_INF);
    vec3 emitted_first = vec3(0.0);
    uint depth = p.depth;
    shade_path = path;
    shade_shadows = 0u;
    bool goes_on = path_shade(p, h.y != WAVE_MISS, hit, pixel, sample_index, albedo, normal_depth, emitted_first);
    if (depth == 0u) {
        store_fieldf(F_ALBEDO, path, albedo);
        store_fieldf(F_NORMAL, path, normal_depth);
        store_fieldf(F_EMITTED, path, vec4(emitted_first, 0.0));
        if (SPLIT_LOBES) {
            // The first hit sets the share and the metallic; later ones keep them.
            store_fieldf(F_SPLIT, path, vec4(p.share, p.metallic));
        }
    }
    store_field(F_RADIANCE, path, uvec4(floatBitsToUint(p.radiance), p.nonfinite));
    if (SPLIT_LOBES) {
        store_fieldf(F_SPECULAR, path, vec4(p.specular, 0.0));
    }
    store_field(F_THROUGHPUT, path, uvec4(floatBitsToUint(p.throughput), shade_shadows));
    if (shade_shadows > 0u) {
        queue_append(shadow_header(params.round), 2u * params.capacity, path);
    }
    if (goes_on) {
        store_fieldf(F_ORIGIN, path, vec4(p.origin, p.prev_pdf));
        store_field(F_DIR, path, uvec4(floatBitsToUint(p.dir), p.depth | p.channel << 16u));
        queue_append(ray_header(params.round + 1u), ((params.round + 1u) & 1u) * params.capacity, path);
    }
}

// Connect: each queued path's shadow rays in the order shade made them, each contribution added
// where its ray is unblocked (one lane a path, so the sum's order is the megakernel's).
void connect() {
    uint path;
    if (!queue_entry(shadow_header(params.round), 2u * params.capacity, path)) {
        return;
    }
    uint count = load_field(F_THROUGHPUT, path).w;
    uvec4 r = load_field(F_RADIANCE, path);
    vec3 radiance = uintBitsToFloat(r.rgb);
    uint nonfinite = r.w;
    vec3 specular = vec3(0.0);
    if (SPLIT_LOBES) {
        specular = load_fieldf(F_SPECULAR, path).rgb;
    }
    for (uint k = 0u; k < count; ++k) {
        int texel = shadow_texel(path, k);
        vec4 origin_tmax = uintBitsToFloat(imageLoad(wf_paths, texel));
        vec3 d = uintBitsToFloat(imageLoad(wf_paths, texel + 1).xyz);
        uvec4 c = imageLoad(wf_paths, texel + 2);
        if (!bvh_any(origin_tmax.xyz, d, 0.0, origin_tmax.w)) {
            vec3 contribution = uintBitsToFloat(c.rgb);
            radiance += contribution;
            nonfinite |= nonfinite_bit(contribution, c.w);
            if (SPLIT_LOBES) {
                specular += uintBitsToFloat(imageLoad(wf_paths, texel + 3).rgb);
            }
        }
    }
    store_field(F_RADIANCE, path, uvec4(floatBitsToUint(radiance), nonfinite));
    if (SPLIT_LOBES) {
        store_fieldf(F_SPECULAR, path, vec4(specular, 0.0));
    }
    count_marches();
}

// Accumulate: the wave's samples of each pixel into the running mean and its second moment, the
// AOVs and (SPLIT_LOBES) the lobe split as pathtrace.comp's trace_pixel.
void accumulate() {
    uvec2 region_pixel = tile_pixel();
    if (any(greaterThanEqual(region_pixel, params.size))) {
        return;
    }
    uint pixels = params.size.x * params.size.y;
    uint wave_index = region_pixel.y * params.size.x + region_pixel.x;
    uint index = wave_index + params.first_row * params.size.x;  // in the accumulation buffers
    uint count = params.sample_count;
    SampleSums sums = no_samples();
    for (uint j = 0u; j < count; ++j) {
        uint path = j * pixels + wave_index;
        uvec4 r = load_field(F_RADIANCE, path);
        vec3 specular = vec3(0.0);
        float metallic = 0.0;
        if (SPLIT_LOBES) {
            specular = load_fieldf(F_SPECULAR, path).rgb;
            metallic = load_fieldf(F_SPLIT, path).w;
        }
        fold_sample(sums, uintBitsToFloat(r.rgb), load_fieldf(F_EMITTED, path).rgb, r.w, load_fieldf(F_ALBEDO, path),
                    specular, metallic);
    }
    accumulate_sums(index, count, sums, load_fieldf(F_NORMAL, wave_index));
}

void main() {
    if (WF_CAMERA_RAYS) {
        camera_rays();
    }
    if (WF_EXTEND) {
        extend();
    }
    if (WF_SHADE) {
        shade();
    }
    if (WF_CONNECT) {
        connect();
    }
    if (WF_ACCUMULATE) {
        accumulate();
    }
}
