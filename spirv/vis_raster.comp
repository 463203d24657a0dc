#version 460
// The visibility buffer, step 4: shadow_raster.comp's tiles (raster_tile.glsl) with the camera as
// the layer. Each pixel's nearest large triangle is merged with what the small ones left in the
// visibility buffer (each pixel by its one owner: no atomic needed).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "kernel/vis_raster.glsl"

KERNEL_LOCAL_SIZE;

const bool BECKMANN = false;
const bool GGX_WALTER = false;
#include "shading.glsl"
#include "shadow_raster.glsl"
#include "visibility.glsl"

// A triangle bounds the tile's depth only where it lies wholly in front of the camera (its
// covered pixels' depths are then positive, none clamped).
bool raster_bounds(vec3 depths) { return min(depths.x, min(depths.y, depths.z)) > 0.0; }

void raster_store(uint index, float depth, uint tri) {
    if (tri != RASTER_NO_TRIANGLE) {
        uint64_t large = vis_pack(depth, tri);
        uint64_t small = visibility[index];
        visibility[index] = large < small ? large : small;
    }
}

#include "raster_tile.glsl"

void main() { raster_tile(); }
