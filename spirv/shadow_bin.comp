#version 460
// Shadow maps, binning: one invocation per BVH triangle enters it in the list of every tile of
// the layer its box overlaps (`FILL`), or counts it there first (the two passes around
// shadow_scan.comp's prefix sum). Triangles appear in BVH order, pieces of a presplit triangle
// once each (they rasterize to the same depth).
#extension GL_GOOGLE_include_directive : require
#include "kernel/shadow_bin.glsl"

layout(local_size_x = 64) in;

#include "bvh.glsl"
#include "shadow_raster.glsl"

void main() {
    uint tri = gl_GlobalInvocationID.x;
    if (tri >= params.tri_count) {
        return;
    }
    uvec4 range;
    if (!shadow_tile_range(shadow_vertex(tri, 0u), shadow_vertex(tri, 1u), shadow_vertex(tri, 2u), range)) {
        return;
    }
    for (uint ty = range.y; ty <= range.w; ++ty) {
        for (uint tx = range.x; tx <= range.z; ++tx) {
            uint t = ty * params.tiles + tx;
            if (FILL) {
                uint slot = tile_start[t] + atomicAdd(tile_count[t], 1u);
                if (slot < params.capacity) {
                    tile_tris[slot] = tri;
                }
            } else {
                atomicAdd(tile_count[t], 1u);
            }
        }
    }
}
