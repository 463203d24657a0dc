#version 460
// values_out[i] = 3 * values_in[i] + add: exercises storage buffers, push descriptors and
// push constants in the foundation tests.
#extension GL_GOOGLE_include_directive : require
#include "kernel/test_buffer.glsl"

KERNEL_LOCAL_SIZE;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) {
        return;
    }
    values_out[i] = 3u * values_in[i] + params.add;
}
