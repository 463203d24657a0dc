// The pixel an invocation of an 8×8 workgroup shades: its lanes in 4×2 blocks rather than rows.
// llvmpipe runs 8 invocations in consecutive order as one SIMD batch, whose cost is that of its
// slowest lane, and 4×2 pixels' rays diverge less than 8×1's (docs/history/2026-11-30.md, second
// round: +5-7 % primary rays/s on Sponza); a 32-wide GPU warp still covers an 8×4 block. Local
// index bits: 0-1 x in the block, 2 y in the block, 3 the block's x, 4-5 its y.
#ifndef UMBRA_PIXEL_GLSL
#define UMBRA_PIXEL_GLSL

uvec2 tile_pixel() {
    uint i = gl_LocalInvocationIndex;
    uvec2 in_tile = uvec2((i & 3u) | ((i >> 1u) & 4u), ((i >> 2u) & 1u) | ((i >> 3u) & 6u));
    return gl_WorkGroupID.xy * 8u + in_tile;
}

#endif
