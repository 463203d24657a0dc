#version 460
// One level of the box chain (ibl.glsl): chain level k = `src.z` >= 1 from level k - 1 (the source
// map when k = 1), each texel the solid-angle weighted mean of its 2x2 parents (clamped at the
// edges of a level that is already one texel wide or high).
#extension GL_GOOGLE_include_directive : require
#include "kernel/ibl_downsample.glsl"

KERNEL_LOCAL_SIZE;

#include "environment.glsl"
#include "ibl.glsl"

vec3 parent(uint k, uvec2 xy, uvec2 size) {
    uint i = xy.y * size.x + xy.x;
    return k == 0u ? env_value(i).rgb : chain[chain_offset(k, params.src_size) + i].rgb;
}

void main() {
    uvec2 xy = gl_GlobalInvocationID.xy;
    uvec2 src = params.src_size;
    uint k = params.src_level;
    uvec2 size = chain_size(k, src);
    if (any(greaterThanEqual(xy, size))) {
        return;
    }
    uvec2 psize = chain_size(k - 1u, src);
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    for (uint dy = 0u; dy < 2u; ++dy) {
        uint y = min(2u * xy.y + dy, psize.y - 1u);
        float w = sin(PI * (float(y) + 0.5) / float(psize.y));
        for (uint dx = 0u; dx < 2u; ++dx) {
            uint x = min(2u * xy.x + dx, psize.x - 1u);
            sum += w * parent(k - 1u, uvec2(x, y), psize);
            weight += w;
        }
    }
    chain[chain_offset(k, src) + xy.y * size.x + xy.x] = vec4(sum / weight, 1.0);
}
