#version 460
// Declares every struct of layout.glsl in a buffer so that tests/layout.rs can read their
// offsets from the SPIR-V, even those whose kernels naga cannot parse. Never dispatched.
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = 1) in;

layout(set = 0, binding = 0, std430) buffer PatternParamsBuffer { PatternParams pattern_params[]; };

layout(set = 0, binding = 1, std430) buffer BufferTestParamsBuffer { BufferTestParams buffer_test_params[]; };

void main() {
    pattern_params[0].seed += 1u;
    buffer_test_params[0].add += 1u;
}
