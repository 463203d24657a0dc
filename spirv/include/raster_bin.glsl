// The binning half of the compute rasterizer (shadow_bin.comp for shadow maps, vis_bin.comp for
// the camera's visibility buffer; shadow_bin.comp documents the steps): one invocation per scene
// triangle (`FILL` false) or per large triangle the count listed (`FILL` true). The including
// kernel defines, before including this file, what a covered texel of a small triangle does:
// `bool raster_accept(uint tri, float depth, vec2 bary, uvec2 texel)` (whether the triangle is
// there: its alpha test, a depth range) and `void raster_direct(uint index, float depth, uint
// tri)` (the atomicMin into the scratch layer at `index`).
#ifndef UMBRA_RASTER_BIN_GLSL
#define UMBRA_RASTER_BIN_GLSL

#include "shadow_raster.glsl"

void raster_bin() {
    uint words = SHADOW_DISPATCH_WORDS * (params.list_at / (params.tiles * params.tiles));
    uint tri;
    if (FILL) {
        if (gl_GlobalInvocationID.x >= tile_dispatch[words + 7u]) {
            return;
        }
        tri = large_tris[gl_GlobalInvocationID.x];
    } else {
        if (gl_GlobalInvocationID.x >= params.tri_count) {
            return;
        }
        tri = raster_tris[gl_GlobalInvocationID.x];
    }
    vec4 a = shadow_vertex(tri, 0u);
    vec4 b = shadow_vertex(tri, 1u);
    vec4 c = shadow_vertex(tri, 2u);
    uvec4 box;
    bool bounded;
    if (!shadow_texel_box(a, b, c, box, bounded)) {
        return;
    }
    bool direct = bounded && all(lessThan(box.zw - box.xy, uvec2(SHADOW_DIRECT_SPAN)));
    // A direct triangle's box spans at most 2 × 2 tiles: bit (x ≠ first column) | (y ≠ first
    // row) << 1 set where that tile is marked (read once here, not per texel: on llvmpipe a
    // storage-buffer read is a loop over the lanes).
    uint marked = 0u;
    uvec2 first_tile = box.xy / SHADOW_TILE;
    if (direct) {
        if (FILL) {
            return;
        }
        uvec2 last_tile = box.zw / SHADOW_TILE;
        uint row0 = params.list_at + first_tile.y * params.tiles;
        uint row1 = params.list_at + last_tile.y * params.tiles;
        marked = uint(tile_marks[row0 + first_tile.x] != 0u) | uint(tile_marks[row0 + last_tile.x] != 0u) << 1u
            | uint(tile_marks[row1 + first_tile.x] != 0u) << 2u | uint(tile_marks[row1 + last_tile.x] != 0u) << 3u;
        // None marked: nothing to do.
        if (marked == 0u) {
            return;
        }
    }
    vec3 e0;
    vec3 e1;
    vec3 e2;
    if (!shadow_edges(a, b, c, e0, e1, e2)) {
        return;
    }
    if (direct) {
        vec3 d = vec3(a.z, b.z, c.z);
        for (uint y = box.y; y <= box.w; ++y) {
            for (uint x = box.x; x <= box.z; ++x) {
                // Only listed tiles' texels: shadow_raster.comp merges and resets just those.
                uint corner = uint(x / SHADOW_TILE != first_tile.x) | uint(y / SHADOW_TILE != first_tile.y) << 1u;
                if (((marked >> corner) & 1u) == 0u) {
                    continue;
                }
                float depth;
                vec2 bary;
                if (shadow_covers(e0, e1, e2, d, uvec2(x, y), depth, bary) && raster_accept(tri, depth, bary, uvec2(x, y))) {
                    raster_direct(y * params.size + x, depth, tri);
                }
            }
        }
        return;
    }
    if (FILL) {
        tile_setup[3u * tri] = vec4(e0, a.z);
        tile_setup[3u * tri + 1u] = vec4(e1, b.z);
        tile_setup[3u * tri + 2u] = vec4(e2, c.z);
    }
    uvec4 range = box / SHADOW_TILE;
    bool entered = false;
    for (uint ty = range.y; ty <= range.w; ++ty) {
        for (uint tx = range.x; tx <= range.z; ++tx) {
            uint t = ty * params.tiles + tx;
            if (tile_marks[params.list_at + t] == 0u) {
                continue;
            }
            // Skip a tile wholly outside one edge (at all four corner texel centres: the edge
            // function is linear, so at every centre between them too).
            vec2 lo = vec2(uvec2(tx, ty) * SHADOW_TILE) + 0.5;
            vec2 hi = lo + float(SHADOW_TILE - 1u);
            if (shadow_edge_outside(e0, lo, hi) || shadow_edge_outside(e1, lo, hi) || shadow_edge_outside(e2, lo, hi)) {
                continue;
            }
            if (FILL) {
                uint slot = tile_start[t] + atomicAdd(tile_count[t], 1u);
                if (slot < params.capacity) {
                    tile_tris[slot] = tri;
                }
            } else {
                atomicAdd(tile_count[t], 1u);
                entered = true;
            }
        }
    }
    if (FILL) {
        return;
    }
    // Listed for the fill; every 64th entry opens another of its workgroups.
    if (entered) {
        uint n = atomicAdd(tile_dispatch[words + 7u], 1u);
        large_tris[n] = tri;
        if (n % 64u == 0u) {
            atomicAdd(tile_dispatch[words + 4u], 1u);
        }
    }
}

#endif
