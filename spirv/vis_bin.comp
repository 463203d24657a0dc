#version 460
// The visibility buffer, steps 1 (`FILL` false: one invocation per scene triangle) and 3 (`FILL`
// true: per large triangle step 1 listed): shadow_bin.comp's binning (raster_bin.glsl) with the
// camera as the layer (src/passes/visibility.rs sets its rows: pixels, view depth). A small
// triangle writes each pixel it covers with one 64-bit atomicMin of its depth and index
// (visibility.glsl).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#include "kernel/vis_bin.glsl"

KERNEL_LOCAL_SIZE;

const bool BECKMANN = false;
const bool GGX_WALTER = false;
#include "shading.glsl"
#include "shadow_raster.glsl"
#include "visibility.glsl"

void raster_direct(uint index, float depth, uint tri) { atomicMin(visibility[index], vis_pack(depth, tri)); }

#include "raster_bin.glsl"

void main() { raster_bin(); }
