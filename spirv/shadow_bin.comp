#version 460
// Shadow maps, step 1 (`FILL` false: one invocation per scene triangle) and 3 (`FILL` true: per
// large triangle step 1 listed)
// (`raster_tris`: the BVH holds a split triangle once per piece, each the whole triangle). Only
// the layer's marked tiles (`tile_marks`, the ones shadow_tiles.comp lists) are rendered. A
// triangle whose texel box spans at most SHADOW_DIRECT_SPAN texels a side rasterizes itself in
// step 1: it loops over its box and keeps the nearest depth of each covered texel of a marked
// tile in the scratch layer with atomicMin on the float's bits (positive floats order as their
// bits). A larger one counts itself into every marked tile its box overlaps and does not lie
// wholly outside of and appends itself to `large_tris` (step 1), then, the fill running over that
// list alone (an indirect dispatch the appends count), enters itself in their lists and writes its
// edge functions and depths for shadow_raster.comp (step 3, after shadow_scan.comp's prefix sum).
#extension GL_GOOGLE_include_directive : require
#include "kernel/shadow_bin.glsl"

KERNEL_LOCAL_SIZE;

const bool BECKMANN = false;
const bool GGX_WALTER = false;
#include "shading.glsl"
#include "shadow_raster.glsl"

bool raster_accept(uint tri, float depth, vec2 bary, uvec2 texel) { return shadow_opaque(tri, bary, texel); }

// Positive floats order as their bits.
void raster_direct(uint index, float depth, uint tri) { atomicMin(shadow_scratch[index], floatBitsToUint(depth)); }

#include "raster_bin.glsl"

void main() { raster_bin(); }
