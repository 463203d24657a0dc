#version 460
// values_out[i] = 3 * values_in[i] + add: exercises storage buffers, push descriptors and
// push constants in the foundation tests.
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) readonly buffer Input { uint values_in[]; };
layout(set = 0, binding = 1, std430) buffer Output { uint values_out[]; };
layout(push_constant) uniform Push { BufferTestParams params; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) {
        return;
    }
    values_out[i] = 3u * values_in[i] + params.add;
}
