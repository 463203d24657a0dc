#version 460
// Shadow maps, step 0 when the maps render for a view (src/passes/shadow.rs, ShadowView): the
// G-buffer's pixels mark, in the cascade of each directional light the lighting pass will read
// for them, the tiles within `reach` texels of where their points land (the filter's footprint,
// the normal offset and a texel to spare), so the rasterizer renders only tiles some pixel reads
// (Fernando et al. 2001's adaptive shadow maps, Haar 2015's virtual shadow maps: a view-driven
// subset of a large map). A point is the lighting pass's (restir.glsl's gbuffer_point), its
// cascade picked as shadow.glsl's shadow_pick_layer picks it; within a relative 1e-5 of a split
// both cascades are marked, as two kernels' arithmetic may round the view depth apart.
//
// One invocation marks a 2 × 2 block of pixels. Written for llvmpipe's code generation, which a
// profile of this kernel (scripts/jit-profile.py) showed paying most for lane-by-lane work: a
// point's cascade is the count of splits below its depth (no loop over an array indexed per
// lane); the cascades some lane of the subgroup needs are visited one at a time, their rows read
// once (a loop, which llvmpipe leaves when no lane needs more, where an if's body runs for every
// lane); and where the subgroup's tiles in a cascade fit in a box of at most `rounds` tiles a
// lane, the lanes mark that box together, a store each a round, instead of each lane looping
// over its own points' tiles (a storage-buffer access is a loop over the SIMD lanes there). The
// box is a superset of the tiles the points need; a subgroup whose box is larger (its pixels far
// apart in the map: a depth edge) marks point by point. Caching the cascades in shared memory
// behind barriers measured 4× slower. Every mark is the same plain store of 1, made only where
// the tile reads 0 (a store to a line other cores share would take it from them): the races
// between pixels are benign.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_EXT_control_flow_attributes : require
#include "kernel/shadow_mark.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

#include "camera.glsl"
#include "shadow_layers.glsl"

// The tile range (t0, t1, inclusive) within `reach` texels of p in a layer with rows r0, r1, r3
// and `size` texels a side; false where p does not project into it.
bool tile_range(vec4 r0, vec4 r1, vec4 r3, uint size, vec3 p, out uvec2 t0, out uvec2 t1) {
    vec4 p1 = vec4(p, 1.0);
    float w = dot(r3, p1);
    vec2 uv = vec2(dot(r0, p1), dot(r1, p1)) / w;
    float edge = float(size) - 1.0;
    t0 = uvec2(clamp(floor(uv - params.reach), vec2(0.0), vec2(edge))) / SHADOW_TILE;
    t1 = uvec2(clamp(floor(uv + params.reach), vec2(0.0), vec2(edge))) / SHADOW_TILE;
    return w > 0.0 && !any(isnan(uv));
}

// Marks tile (x, y) of the layer whose tiles start at `at`.
void mark(uint at, uint x, uint y) {
    uint i = at + y * params.tiles + x;
    if (tile_marks[i] == 0u) {
        tile_marks[i] = 1u;
    }
}

void main() {
    // The block's points and view depths (0: no point).
    vec3 points[4];
    float depths[4];
    [[unroll]] for (uint q = 0u; q < 4u; ++q) {
        ivec2 pixel = ivec2(gl_GlobalInvocationID.xy * 2u + uvec2(q & 1u, q >> 1u));
        float depth = all(lessThan(uvec2(pixel), params.size)) ? imageLoad(gb_depth, pixel).x : 0.0;
        depths[q] = 0.0;
        if (depth > 0.0) {
            vec3 origin;
            vec3 dir;
            camera_ray(params.camera.origin, params.camera.forward, params.camera.right, params.camera.up,
                       params.camera.orthographic != 0u, vec2(pixel) + 0.5, params.size, origin, dir);
            points[q] = origin + dir * (depth / dot(dir, params.camera.forward));
            // (Positive: the point lies in front of the camera.)
            depths[q] = max(dot(points[q] - params.camera.origin, params.camera.forward), 1e-30);
        }
    }
    for (uint k = 0u; k < params.lights; ++k) {
        uvec4 rec = imageLoad(shadow_texels, int(SHADOW_HEADER_TEXELS + k));
        if (rec.z != SHADOW_LIGHT_CASCADES) {
            continue;
        }
        uint count = min(rec.y, SHADOW_MAX_CASCADES);
        // Each point's cascade at its view depth a little nearer and a little farther: the count
        // of splits below it (the splits ascend, so this is the first cascade whose split lies
        // at or beyond it); `count`: beyond the last, or no point.
        vec4 d = vec4(depths[0], depths[1], depths[2], depths[3]);
        uvec4 near = mix(uvec4(count), uvec4(0u), greaterThan(d, vec4(0.0)));
        uvec4 far = near;
        for (uint j = 0u; j < count; ++j) {
            float split = shadow_header(rec.x + SHADOW_LAYER_TEXELS * j + 5u).z;
            near += uvec4(lessThan(vec4(split), d * (1.0 - 1e-5)));
            far += uvec4(lessThan(vec4(split), d * (1.0 + 1e-5)));
        }
        // The cascades some lane of the subgroup needs, one at a time (a loop, which llvmpipe
        // leaves when no lane is left in it, not an if, whose body it runs for every lane).
        uint needed = 0u;
        [[unroll]] for (uint q = 0u; q < 4u; ++q) {
            needed |= ((1u << near[q]) | (1u << far[q])) & ((1u << count) - 1u);
        }
        needed = subgroupOr(needed);
        uint first = (rec.x - params.layers_at) / SHADOW_LAYER_TEXELS;
        while (needed != 0u) {
            uint j = findLSB(needed);
            needed &= needed - 1u;
            uint at = rec.x + SHADOW_LAYER_TEXELS * j;
            vec4 r0 = shadow_header(at);
            vec4 r1 = shadow_header(at + 1u);
            vec4 r3 = shadow_header(at + 3u);
            uint size = imageLoad(shadow_texels, int(at + 4u)).y;
            // This lane's tiles in cascade j: per point, and their union.
            uvec2 t0[4];
            uvec2 t1[4];
            bool in_j[4];
            uvec2 lo = uvec2(0xffffu);
            uvec2 hi = uvec2(0u);
            [[unroll]] for (uint q = 0u; q < 4u; ++q) {
                in_j[q] = (near[q] == j || far[q] == j)
                    && tile_range(r0, r1, r3, size, points[q], t0[q], t1[q]);
                if (in_j[q]) {
                    lo = min(lo, t0[q]);
                    hi = max(hi, t1[q]);
                }
            }
            uint tiles_at = (first + j) * params.tiles * params.tiles;
            // The subgroup's union: where it is at most params.rounds tiles a lane (4 by
            // default: PCSS's reach makes a point's own range 3 × 3 tiles or more), the lanes
            // mark it together (a store each a round, a superset of the tiles their points
            // need); otherwise each lane marks its points' own tiles.
            uvec2 all_lo = subgroupMin(lo);
            uvec2 all_hi = subgroupMax(hi);
            if (all(lessThanEqual(all_lo, all_hi))) {
                uvec2 extent = all_hi - all_lo + 1u;
                uint area = extent.x * extent.y;
                if (area <= params.rounds * gl_SubgroupSize) {
                    for (uint i = gl_SubgroupInvocationID; i < area; i += gl_SubgroupSize) {
                        mark(tiles_at, all_lo.x + i % extent.x, all_lo.y + i / extent.x);
                    }
                } else {
                    [[unroll]] for (uint q = 0u; q < 4u; ++q) {
                        if (in_j[q]) {
                            for (uint y = t0[q].y; y <= t1[q].y; ++y) {
                                for (uint x = t0[q].x; x <= t1[q].x; ++x) {
                                    mark(tiles_at, x, y);
                                }
                            }
                        }
                    }
                }
            }
        }
    }
}
