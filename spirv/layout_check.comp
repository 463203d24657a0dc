#version 460
// Declares every struct of layout.glsl in a buffer so that tests/layout.rs can read their
// offsets from the SPIR-V, even those whose kernels naga cannot parse. Never dispatched.
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = 1) in;

layout(set = 0, binding = 0, std430) buffer PatternParamsBuffer { PatternParams pattern_params[]; };

layout(set = 0, binding = 1, std430) buffer BufferTestParamsBuffer { BufferTestParams buffer_test_params[]; };
layout(set = 0, binding = 2, std430) buffer BvhNodeBuffer { BvhNode bvh_node_check[]; };
layout(set = 0, binding = 3, std430) buffer BvhTriBuffer { BvhTri bvh_tri_check[]; };
layout(set = 0, binding = 4, std430) buffer TraceRayBuffer { TraceRay trace_ray_check[]; };
layout(set = 0, binding = 5, std430) buffer TraceHitBuffer { TraceHit trace_hit_check[]; };
layout(set = 0, binding = 6, std430) buffer TraceParamsBuffer { TraceParams trace_params_check[]; };

void main() {
    pattern_params[0].seed += 1u;
    buffer_test_params[0].add += 1u;
    bvh_node_check[0].tri_count += 1u;
    bvh_tri_check[0].v0.x += 1.0;
    trace_ray_check[0].origin_tmin.x += 1.0;
    trace_hit_check[0].tri += 1u;
    trace_params_check[0].count += 1u;
}
