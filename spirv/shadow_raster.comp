#version 460
// Shadow maps, step 4: one workgroup per listed tile of SHADOW_TILE² texels (an indirect dispatch
// over shadow_tiles.comp's list), one invocation per QUAD × QUAD texels, over the large
// triangles in the tile's list (shadow_bin.comp, which also wrote their edge functions and
// depths). Each invocation tests its texel centres against them (shadow_raster.glsl: watertight
// edge functions, a tie rule), keeps the nearest depth of each, merges the small triangles'
// depth from the scratch layer (and resets it for the next layer), and writes its texels of the
// map: every texel once, by its owner, so the result does not depend on the lists' order.
// (Setting the triangles up in shared memory instead, 256 at a time behind barriers, measured
// 20 % slower on lavapipe.)
//
// Before that, the workgroup culls the list by depth (a tile's hierarchical Z): every opaque
// triangle of the list that covers all the tile's texel centres bounds the tile's depth by its
// farthest depth over them (shadow_covers_box), and a triangle whose every vertex lies beyond the
// nearest such bound can win no texel of the tile (its depth anywhere is a blend of its
// vertices'). The survivors go to shared memory, and each texel tests only them: from the sun,
// Sponza's roofs hide the arcades, floors and arches stacked under them. More survivors than
// SHADOW_SURVIVORS: every texel tests the whole list, as without the cull.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "kernel/shadow_raster.glsl"

// Each invocation owns a QUAD × QUAD block of the tile's texels, so that one read of a
// triangle's set-up (three texel fetches, on llvmpipe a gather each: most of a test's cost)
// serves QUAD² texel tests. 2 keeps 64 invocations a tile, two warps on a GPU; 4 × 4 (16
// invocations, half of a 32-wide warp idle) measured 10–30 % faster on lavapipe in one noisy
// run, 4 × 2 no faster in a quieter one (docs/history/2026-12-04.md, third session).
const uint QUAD = SHADOW_QUAD;
const uint QUAD_TEXELS = QUAD * QUAD;
KERNEL_LOCAL_SIZE;

const uint SHADOW_SURVIVORS = 1024u;
shared uint tile_bound;
shared uint survivor_count;
shared uint survivors[SHADOW_SURVIVORS];

const bool BECKMANN = false;
const bool GGX_WALTER = false;
#include "shading.glsl"
#include "shadow_raster.glsl"

void main() {
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
        if (shadow_covers_box(r0.xyz, r1.xyz, r2.xyz, vec3(r0.w, r1.w, r2.w), lo, hi, far)) {
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
    [[unroll]] for (uint k = 0u; k < QUAD_TEXELS; ++k) {
        nearest[k] = BVH_INF;
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
                && depth < nearest[k] && shadow_opaque(tri, bary, texel)) {
                nearest[k] = depth;
            }
        }
    }
    [[unroll]] for (uint k = 0u; k < QUAD_TEXELS; ++k) {
        uvec2 texel = base + uvec2(k % QUAD, k / QUAD);
        if (all(lessThan(texel, uvec2(params.size)))) {
            uint i = texel.y * params.size + texel.x;
            float near = min(nearest[k], uintBitsToFloat(shadow_scratch[i]));
            shadow_scratch[i] = floatBitsToUint(BVH_INF);
            imageStore(shadow_depth, int(params.offset + i), vec4(near));
        }
    }
}
