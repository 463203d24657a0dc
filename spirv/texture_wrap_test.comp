#version 460
// Test kernel: texture.glsl's repeat and mirrored-repeat wrapping of integer texel coordinates
// (texture_wrap, whose modulo avoids integer division), for pairs (i, size) from the host:
// out[2k] = repeat, out[2k + 1] = mirror. tests/texture_wrap.rs compares them with Rust's exact
// rem_euclid.
#extension GL_GOOGLE_include_directive : require
#include "kernel/texture_wrap_test.glsl"

KERNEL_LOCAL_SIZE;


#include "texture.glsl"

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= params.count) {
        return;
    }
    ivec2 c = cases[k];
    wrapped[2u * k] = texture_wrap(c.x, c.y, false, false);
    wrapped[2u * k + 1u] = texture_wrap(c.x, c.y, false, true);
}
