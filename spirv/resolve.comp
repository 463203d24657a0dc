#version 460
// The path tracer's running mean (an RGBA32F buffer, row-major) into a storage image: how an
// embedding host gets a progressive path-traced frame into its own image (src/embed.rs).
#extension GL_GOOGLE_include_directive : require
#include "kernel/resolve.glsl"

KERNEL_LOCAL_SIZE;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, params.size))) {
        return;
    }
    imageStore(out_color, ivec2(pixel), accum[pixel.y * params.size.x + pixel.x]);
}
