// The camera's visibility buffer (vis_bin.comp, vis_raster.comp): the shadow rasterizer's hooks
// (raster_bin.glsl, raster_tile.glsl) for a camera layer, whose texels are pixels, whose depth is
// the view depth along the camera's forward axis and whose entries pack that depth's bits above
// the triangle's BVH index, so one 64-bit atomicMin keeps the nearest (positive floats order as
// their bits; equally near triangles by the lower index). The G-buffer kernel resolves it.
#ifndef UMBRA_VISIBILITY_GLSL
#define UMBRA_VISIBILITY_GLSL

uint64_t vis_pack(float depth, uint tri) { return (uint64_t(floatBitsToUint(depth)) << 32) | uint64_t(tri); }

// A surface in front of the camera (shadow_covers clamps depths behind it to 0: an orthographic
// camera's plane cuts as a ray cast from it does), not cut out by its alpha test (as the
// traversal cuts; the masks' test at the rasterizer's barycentrics).
bool raster_accept(uint tri, float depth, vec2 bary, uvec2 texel) {
    return depth > 0.0 && shadow_opaque(tri, bary, texel);
}

#endif
