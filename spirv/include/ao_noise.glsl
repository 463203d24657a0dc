// The screen-space AO kernels' per-pixel pattern (ssao.comp, gtao.comp): a value in (0, 1) from
// the 4x4 Bayer matrix over each 4x4 tile of AO texels, so the tile holds 16 distinct rotations
// (or offsets) of the kernel, which ao_blur.comp's 4x4 window averages away.
#ifndef UMBRA_AO_NOISE_GLSL
#define UMBRA_AO_NOISE_GLSL

const uint BAYER4[16] = uint[16](0u, 8u, 2u, 10u, 12u, 4u, 14u, 6u, 3u, 11u, 1u, 9u, 15u, 7u, 13u, 5u);

float ao_tile_noise(ivec2 texel) {
    return (float(BAYER4[(texel.y & 3) * 4 + (texel.x & 3)]) + 0.5) / 16.0;
}

#endif
