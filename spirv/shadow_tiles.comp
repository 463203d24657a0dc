#version 460
// Shadow maps, per layer before binning: the marked tiles of the layer's window (all of them when
// the maps render without a view; shadow_mark.comp's otherwise) listed at `list_at`, and their
// count as the x of the layer's indirect dispatch (`tile_dispatch`, SHADOW_DISPATCH_WORDS a layer:
// x, y, z and a pad, then the fill's dispatch, whose y and z are set here) that shadow_raster.comp
// and shadow_moments.comp run over. The list's order depends on the atomics' order, but each tile's
// workgroup writes only its own texels.
#extension GL_GOOGLE_include_directive : require
#include "kernel/shadow_tiles.glsl"
#include "shadow_pack.glsl"

KERNEL_LOCAL_SIZE;

void main() {
    uvec2 lo = shadow_unpack(params.window_lo);
    uvec2 hi = shadow_unpack(params.window_hi);
    uvec2 tile = gl_GlobalInvocationID.xy + lo;
    uint layer = params.list_at / (params.tiles * params.tiles);
    uint words = SHADOW_DISPATCH_WORDS * layer;
    if (gl_GlobalInvocationID.xy == uvec2(0u)) {
        tile_dispatch[words + 1u] = 1u;
        tile_dispatch[words + 2u] = 1u;
        tile_dispatch[words + 5u] = 1u;
        tile_dispatch[words + 6u] = 1u;
    }
    if (any(greaterThan(tile, hi))) {
        return;
    }
    uint t = tile.y * params.tiles + tile.x;
    if (tile_marks[params.list_at + t] != 0u) {
        tile_list[params.list_at + atomicAdd(tile_dispatch[words], 1u)] = t;
    }
}
