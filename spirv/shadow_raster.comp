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

KERNEL_LOCAL_SIZE;

const bool BECKMANN = false;
const bool GGX_WALTER = false;
#include "shading.glsl"
#include "shadow_raster.glsl"

bool raster_accept(uint tri, float depth, vec2 bary, uvec2 texel) { return shadow_opaque(tri, bary, texel); }

bool raster_bounds(vec3 depths) { return true; }

// The nearest of the large and the small triangles' depths, the scratch reset for the next layer.
void raster_store(uint index, float depth, uint tri) {
    float near = min(depth, uintBitsToFloat(shadow_scratch[index]));
    shadow_scratch[index] = floatBitsToUint(BVH_INF);
    imageStore(shadow_depth, int(params.offset + index), vec4(near));
}

#include "raster_tile.glsl"

void main() { raster_tile(); }
