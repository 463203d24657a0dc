// A pair of 16-bit coordinates packed as x | y << 16 (src/passes/shadow.rs, pack_pair): the
// shadow rasterizer's windows and the moment filter's texel bounds.
#ifndef UMBRA_SHADOW_PACK_GLSL
#define UMBRA_SHADOW_PACK_GLSL

uvec2 shadow_unpack(uint packed) {
    return uvec2(packed & 0xffffu, packed >> 16);
}

#endif
