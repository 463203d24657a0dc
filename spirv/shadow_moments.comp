#version 460
// Moment shadow maps (Peters and Klein 2015): the layer's depth as its four power moments
// (z, z², z³, z⁴) of the depth mapped to [0, 1] (empty texels at 1), box-filtered over
// (2 radius + 1)² texels in two separable passes (along x from the depth map, then along y).
// One workgroup per tile the rasterizer rendered (the indirect dispatch over shadow_tiles.comp's
// list), one invocation per texel; the taps clamp to the layer's window (`first`, `last`), as the
// texels outside are undefined. Texels of a rendered tile near an unrendered one blend undefined
// depths, but no pixel reads them: the view's marks reach a filter's radius past what it reads.
#extension GL_GOOGLE_include_directive : require
#include "kernel/shadow_moments.glsl"
#include "shadow_pack.glsl"

KERNEL_LOCAL_SIZE;

vec4 moments_at(ivec2 q) {
    int size = int(params.size);
    q = clamp(q, ivec2(shadow_unpack(params.first)), ivec2(shadow_unpack(params.last)));
    int index = int(params.offset) + q.y * size + q.x;
    if (params.direction == 0u) {
        float z = clamp(imageLoad(shadow_depth, index).x / params.depth_far, 0.0, 1.0);
        float z2 = z * z;
        return vec4(z, z2, z2 * z, z2 * z2);
    }
    return imageLoad(moments_x, index);
}

void main() {
    uint tiles = (params.size + SHADOW_TILE - 1u) / SHADOW_TILE;
    uint listed = tile_list[params.list_at + gl_WorkGroupID.x];
    ivec2 texel = ivec2(uvec2(listed % tiles, listed / tiles) * SHADOW_TILE + gl_LocalInvocationID.xy);
    int size = int(params.size);
    if (any(greaterThan(texel, ivec2(shadow_unpack(params.last))))) {
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
