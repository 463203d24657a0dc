#version 460
// Moment shadow maps (Peters and Klein 2015): the layer's depth as its four power moments
// (z, z², z³, z⁴) of the depth mapped to [0, 1] (empty texels at 1), box-filtered over
// (2 radius + 1)² texels in two separable passes (along x from the depth map, then along y).
// The filter stays inside the layer (taps clamp to its edge).
#extension GL_GOOGLE_include_directive : require
#include "kernel/shadow_moments.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

vec4 moments_at(ivec2 q) {
    int size = int(params.size);
    q = clamp(q, ivec2(0), ivec2(size - 1));
    int index = int(params.offset) + q.y * size + q.x;
    if (params.direction == 0u) {
        float z = clamp(imageLoad(shadow_depth, index).x / params.depth_far, 0.0, 1.0);
        float z2 = z * z;
        return vec4(z, z2, z2 * z, z2 * z2);
    }
    return imageLoad(moments_x, index);
}

void main() {
    ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
    int size = int(params.size);
    if (any(greaterThanEqual(texel, ivec2(size)))) {
        return;
    }
    int r = int(params.radius);
    ivec2 axis = params.direction == 0u ? ivec2(1, 0) : ivec2(0, 1);
    vec4 sum = vec4(0.0);
    for (int k = -r; k <= r; ++k) {
        sum += moments_at(texel + k * axis);
    }
    vec4 mean = sum / float(2 * r + 1);
    int index = int(params.offset) + texel.y * size + texel.x;
    if (params.direction == 0u) {
        imageStore(moments_x, index, mean);
    } else {
        imageStore(shadow_moments, index, mean);
    }
}
