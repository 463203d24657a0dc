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
// One invocation marks for a block of SHADOW_MARK_BLOCK² pixels, from their view depths' range
// alone: at one view depth a pixel's point is affine in its image position, and linear in the
// depth along its ray, so every point of the block within a depth range lies in the hull of the
// 8 points its corner pixels' rays reach at the range's ends, and a layer's projection (a
// directional light's is affine) keeps it in the box of their projections. A block's depth range
// is cut to each cascade's (widened by 2e-5 against the splits' rounding), so a block across a
// split marks each cascade's part. Most blocks lie on one surface and their box is the tiles
// their points need, or a few more; a block across a depth edge (its range long: a box of more
// than `box_limit` tiles) marks point by point instead, as does one whose projection is not
// affine.
//
// Written for llvmpipe's code generation, which a profile of this kernel (scripts/jit-profile.py)
// showed paying most for lane-by-lane work: a block's cascades are the counts of splits below its
// depths (no loop over an array indexed per lane); the cascades some lane of the subgroup needs
// are visited one at a time, their rows read once (a loop, which llvmpipe leaves when no lane
// needs more, where an if's body runs for every lane); and where the subgroup's boxes in a
// cascade fit in a box of at most `rounds` tiles a lane, the lanes mark that box together, a
// store each a round, instead of each lane looping over its own box (a storage-buffer access
// is a loop over the SIMD lanes there). Caching the cascades in shared memory behind barriers
// measured 4× slower. Every mark is the same plain store of 1, made only where the tile reads 0
// (a store to a line other cores share would take it from them): the races between pixels are
// benign.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_EXT_control_flow_attributes : require
#include "kernel/shadow_mark.glsl"

KERNEL_LOCAL_SIZE;

#include "camera.glsl"
#include "shadow_layers.glsl"

const uint BLOCK = SHADOW_MARK_BLOCK;

// The tile range (t0, t1, inclusive) within `reach` texels of the layer positions lo..hi in a
// layer of `size` texels a side.
void tile_box(vec2 lo, vec2 hi, uint size, out uvec2 t0, out uvec2 t1) {
    float edge = float(size) - 1.0;
    t0 = uvec2(clamp(floor(lo - params.reach), vec2(0.0), vec2(edge))) / SHADOW_TILE;
    t1 = uvec2(clamp(floor(hi + params.reach), vec2(0.0), vec2(edge))) / SHADOW_TILE;
}

// Point p's layer position in a layer with rows r0, r1, r3; false where p does not project.
bool project(vec4 r0, vec4 r1, vec4 r3, vec3 p, out vec2 uv) {
    vec4 p1 = vec4(p, 1.0);
    float w = dot(r3, p1);
    uv = vec2(dot(r0, p1), dot(r1, p1)) / w;
    return w > 0.0 && !any(isnan(uv));
}

// The world point at view depth `depth` on the ray through image position `pos`.
vec3 view_point(vec2 pos, float depth) {
    return camera_point(params.camera.origin, params.camera.forward, params.camera.right, params.camera.up,
                        camera_orthographic(params.camera.flags), pos, params.size, depth);
}

// Marks tile (x, y) of the layer whose tiles start at `at`.
void mark(uint at, uint x, uint y) {
    uint i = at + y * params.tiles + x;
    if (tile_marks[i] == 0u) {
        tile_marks[i] = 1u;
    }
}

// The G-buffer's view depth at the block's pixel q (0: no point, or outside the image).
float block_depth(uvec2 base, uint q) {
    uvec2 pixel = base + uvec2(q % BLOCK, q / BLOCK);
    return all(lessThan(pixel, params.size)) ? imageLoad(gb_depth, ivec2(pixel)).x : 0.0;
}

// The counts of a light's `count` splits (from texel `at`) below depths d.x and d.y: the cascades
// they fall in, each split read once.
uvec2 cascades_at(uint at, uint count, vec2 d) {
    uvec2 c = uvec2(0u);
    for (uint j = 0u; j < count; ++j) {
        c += uvec2(lessThan(vec2(shadow_header(at + SHADOW_LAYER_TEXELS * j + 5u).z), d));
    }
    return c;
}

void main() {
    uvec2 base = gl_GlobalInvocationID.xy * BLOCK;
    // The block's range of view depths over its points.
    float dmin = 3.0e38;
    float dmax = 0.0;
    [[unroll]] for (uint q = 0u; q < BLOCK * BLOCK; ++q) {
        float depth = block_depth(base, q);
        if (depth > 0.0) {
            dmin = min(dmin, depth);
            dmax = max(dmax, depth);
        }
    }
    bool any_point = dmax > 0.0;
    // The block's corner pixels' image positions.
    vec2 c0 = camera_sample(ivec2(base), params.camera.flags);
    vec2 c1 = c0 + float(BLOCK - 1u);
    for (uint k = 0u; k < params.lights; ++k) {
        uvec4 rec = imageLoad(shadow_texels, int(SHADOW_HEADER_TEXELS + k));
        if (rec.z != SHADOW_LIGHT_CASCADES) {
            continue;
        }
        uint count = min(rec.y, SHADOW_MAX_CASCADES);
        // The block's cascades: from its nearest depth a little nearer to its farthest a little
        // farther (`count`: beyond the last).
        uvec2 range = cascades_at(rec.x, count, vec2(dmin * (1.0 - 1e-5), dmax * (1.0 + 1e-5)));
        uint near = any_point ? range.x : count;
        uint far = any_point ? min(range.y, count - 1u) : 0u;
        uint mine = near <= far ? ((2u << far) - (1u << near)) & ((1u << count) - 1u) : 0u;
        // The cascades some lane of the subgroup needs, one at a time (a loop, which llvmpipe
        // leaves when no lane is left in it, not an if, whose body it runs for every lane).
        uint needed = subgroupOr(mine);
        uint first = (rec.x - params.layers_at) / SHADOW_LAYER_TEXELS;
        while (needed != 0u) {
            uint j = findLSB(needed);
            needed &= needed - 1u;
            uint at = rec.x + SHADOW_LAYER_TEXELS * j;
            vec4 r0 = shadow_header(at);
            vec4 r1 = shadow_header(at + 1u);
            vec4 r3 = shadow_header(at + 3u);
            uint size = imageLoad(shadow_texels, int(at + 4u)).y;
            // The block's depths in cascade j (its splits widened by 2e-5), and the box of the
            // hull's 8 corners there.
            float lo_j = j > 0u ? shadow_header(at - SHADOW_LAYER_TEXELS + 5u).z / (1.0 + 2e-5) : 0.0;
            float hi_j = shadow_header(at + 5u).z / (1.0 - 2e-5);
            float d0 = max(dmin, lo_j);
            float d1 = min(dmax, hi_j);
            bool in_j = (mine & (1u << j)) != 0u && d0 <= d1;
            vec2 lo = vec2(3.0e38);
            vec2 hi = vec2(-3.0e38);
            bool affine = true;
            [[unroll]] for (uint c = 0u; c < 8u; ++c) {
                vec2 pos = vec2((c & 1u) != 0u ? c1.x : c0.x, (c & 2u) != 0u ? c1.y : c0.y);
                vec2 uv;
                affine = project(r0, r1, r3, view_point(pos, (c & 4u) != 0u ? d1 : d0), uv) && affine;
                lo = min(lo, uv);
                hi = max(hi, uv);
            }
            uvec2 t0;
            uvec2 t1;
            tile_box(lo, hi, size, t0, t1);
            uvec2 own = t1 - t0 + 1u;
            // Lanes whose box is small join the subgroup's box, or mark their own where the
            // subgroup's is too large; the others mark point by point.
            bool boxed = in_j && affine && own.x * own.y <= params.box_limit;
            bool pointwise = in_j && !boxed;
            uint tiles_at = (first + j) * params.tiles * params.tiles;
            uvec2 all_lo = subgroupMin(boxed ? t0 : uvec2(0xffffu));
            uvec2 all_hi = subgroupMax(boxed ? t1 : uvec2(0u));
            uint own_area = 0u;
            if (all(lessThanEqual(all_lo, all_hi))) {
                uvec2 extent = all_hi - all_lo + 1u;
                uint area = extent.x * extent.y;
                if (area <= params.rounds * gl_SubgroupSize) {
                    for (uint i = gl_SubgroupInvocationID; i < area; i += gl_SubgroupSize) {
                        mark(tiles_at, all_lo.x + i % extent.x, all_lo.y + i / extent.x);
                    }
                } else if (boxed) {
                    own_area = own.x * own.y;
                }
            }
            for (uint i = 0u; i < own_area; ++i) {
                mark(tiles_at, t0.x + i % own.x, t0.y + i / own.x);
            }
            // Point by point: each of the block's points in cascade j marks its own tiles.
            for (uint q = 0u; pointwise && q < BLOCK * BLOCK; ++q) {
                float depth = block_depth(base, q);
                if (depth > 0.0) {
                    vec2 pos = camera_sample(ivec2(base + uvec2(q % BLOCK, q / BLOCK)), params.camera.flags);
                    vec3 p = view_point(pos, depth);
                    // (Positive: the point lies in front of the camera.)
                    float d = max(dot(p - params.camera.origin, params.camera.forward), 1e-30);
                    uvec2 cd = cascades_at(rec.x, count, d * vec2(1.0 - 1e-5, 1.0 + 1e-5));
                    vec2 uv;
                    if (any(equal(cd, uvec2(j))) && project(r0, r1, r3, p, uv)) {
                        uvec2 u0;
                        uvec2 u1;
                        tile_box(uv, uv, size, u0, u1);
                        for (uint y = u0.y; y <= u1.y; ++y) {
                            for (uint x = u0.x; x <= u1.x; ++x) {
                                mark(tiles_at, x, y);
                            }
                        }
                    }
                }
            }
        }
    }
}
