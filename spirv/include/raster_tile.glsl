// The tile half of the compute rasterizer (shadow_raster.comp for shadow maps, vis_raster.comp for
// the camera's visibility buffer; shadow_raster.comp documents the step): one workgroup per
// listed tile, its depth cull, then each texel's nearest large triangle. The including kernel
// defines, before including this file: `bool raster_accept(uint tri, float depth, vec2 bary,
// uvec2 texel)` (as raster_bin.glsl), `bool raster_bounds(vec3 depths)` (whether a triangle with
// these vertex depths that covers the whole tile may bound its depth for the cull) and `void
// raster_store(uint index, float depth, uint tri)` (merges a texel's nearest large triangle,
// RASTER_NO_TRIANGLE at depth BVH_INF where none, with the small ones' scratch at `index` and
// writes the result; each texel once, by its owner).
#ifndef UMBRA_RASTER_TILE_GLSL
#define UMBRA_RASTER_TILE_GLSL

// (The including kernel enables GL_EXT_control_flow_attributes.)
#include "shadow_raster.glsl"

// Each invocation owns a QUAD × QUAD block of the tile's texels, so that one read of a
// triangle's set-up (three texel fetches, on llvmpipe a gather each: most of a test's cost)
// serves QUAD² texel tests. 2 keeps 64 invocations a tile, two warps on a GPU; 4 × 4 (16
// invocations, half of a 32-wide warp idle) measured 10–30 % faster on lavapipe in one noisy
// run, 4 × 2 no faster in a quieter one (docs/history/2026-12-04.md, third session).
const uint QUAD = SHADOW_QUAD;
const uint QUAD_TEXELS = QUAD * QUAD;
const uint SHADOW_SURVIVORS = 1024u;
shared uint tile_bound;
shared uint survivor_count;
shared uint survivors[SHADOW_SURVIVORS];

void raster_tile() {
    // One workgroup per listed tile (shadow_tiles.comp: the window's, or the view's marked ones).
    uint listed = tile_list[params.list_at + gl_WorkGroupID.x];
    uvec2 tile = uvec2(listed % params.tiles, listed / params.tiles);
    uvec2 base = tile * SHADOW_TILE + gl_LocalInvocationID.xy * QUAD;
    uint t = tile.y * params.tiles + tile.x;
    uint start = min(tile_start[t], params.capacity);
    uint count = min(tile_count[t], params.capacity - start);
    // Every invocation has its count: zero it for the next layer's counting pass.
    uint lane = gl_LocalInvocationIndex;
    if (lane == 0u) {
        tile_bound = floatBitsToUint(BVH_INF);
        survivor_count = 0u;
    }
    barrier();
    if (lane == 0u) {
        tile_count[t] = 0u;
    }
    // The cull: the bound from the triangles covering the whole tile (the lanes share the list),
    // then the survivors.
    uint group = (SHADOW_TILE / QUAD) * (SHADOW_TILE / QUAD);
    uvec2 lo = tile * SHADOW_TILE;
    uvec2 hi = min(lo + (SHADOW_TILE - 1u), uvec2(params.size - 1u));
    for (uint j = lane; j < count; j += group) {
        uint tri = tile_tris[start + j];
        if (HAS_ALPHA && floatBitsToUint(bvh_tri_v(tri, 1u).w) != 0u) {
            continue;
        }
        vec4 r0 = imageLoad(setup_texels, int(3u * tri));
        vec4 r1 = imageLoad(setup_texels, int(3u * tri + 1u));
        vec4 r2 = imageLoad(setup_texels, int(3u * tri + 2u));
        float far;
        vec3 d = vec3(r0.w, r1.w, r2.w);
        if (shadow_covers_box(r0.xyz, r1.xyz, r2.xyz, d, lo, hi, far) && raster_bounds(d)) {
            // Depths are clamped at 0: positive floats order as their bits.
            atomicMin(tile_bound, floatBitsToUint(far));
        }
    }
    barrier();
    float bound = uintBitsToFloat(tile_bound);
    for (uint j = lane; j < count; j += group) {
        uint tri = tile_tris[start + j];
        float d0 = imageLoad(setup_texels, int(3u * tri)).w;
        float d1 = imageLoad(setup_texels, int(3u * tri + 1u)).w;
        float d2 = imageLoad(setup_texels, int(3u * tri + 2u)).w;
        if (!(min(d0, min(d1, d2)) > bound)) {
            uint slot = atomicAdd(survivor_count, 1u);
            if (slot < SHADOW_SURVIVORS) {
                survivors[slot] = tri;
            }
        }
    }
    barrier();
    bool culled = survivor_count <= SHADOW_SURVIVORS;
    uint tests = culled ? survivor_count : count;
    float nearest[QUAD_TEXELS];
    uint nearest_tri[QUAD_TEXELS];
    [[unroll]] for (uint k = 0u; k < QUAD_TEXELS; ++k) {
        nearest[k] = BVH_INF;
        nearest_tri[k] = RASTER_NO_TRIANGLE;
    }
    for (uint j = 0u; j < tests; ++j) {
        uint tri = culled ? survivors[j] : tile_tris[start + j];
        vec4 r0 = imageLoad(setup_texels, int(3u * tri));
        vec4 r1 = imageLoad(setup_texels, int(3u * tri + 1u));
        vec4 r2 = imageLoad(setup_texels, int(3u * tri + 2u));
        [[unroll]] for (uint k = 0u; k < QUAD_TEXELS; ++k) {
            uvec2 texel = base + uvec2(k % QUAD, k / QUAD);
            float depth;
            vec2 bary;
            if (shadow_covers(r0.xyz, r1.xyz, r2.xyz, vec3(r0.w, r1.w, r2.w), texel, depth, bary)
                && depth < nearest[k] && raster_accept(tri, depth, bary, texel)) {
                nearest[k] = depth;
                nearest_tri[k] = tri;
            }
        }
    }
    [[unroll]] for (uint k = 0u; k < QUAD_TEXELS; ++k) {
        uvec2 texel = base + uvec2(k % QUAD, k / QUAD);
        if (all(lessThan(texel, uvec2(params.size)))) {
            raster_store(texel.y * params.size + texel.x, nearest[k], nearest_tri[k]);
        }
    }
}

#endif
