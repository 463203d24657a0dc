#version 460
// Writes a known function of the invocation id into an rgba32f image. The foundation test
// recomputes it on the CPU and expects every texel bit-exact.
#extension GL_GOOGLE_include_directive : require
#include "kernel/test_pattern.glsl"

KERNEL_LOCAL_SIZE;

// Multiplies the hash channel: proves specialization constants reach the kernel.

uint pattern_hash(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(p, params.size))) {
        return;
    }
    uint h = pattern_hash(p.x + p.y * params.size.x + params.seed) & 0xffffu;
    imageStore(out_image, ivec2(p),
               vec4(float(p.x), float(p.y), float((p.x * p.y + params.frame) % 65521u),
                    float(h * PATTERN_MULTIPLIER)));
}
