#version 460
// The path tracer's running mean (an RGBA32F buffer, row-major) into a storage image: how an
// embedding host gets a progressive path-traced frame into its own image (src/embed.rs).

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0, std430) readonly buffer Accum { vec4 accum[]; };
layout(set = 0, binding = 1, rgba32f) uniform writeonly image2D out_color;
layout(push_constant) uniform Push { uvec4 size; } push;  // width, height

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(pixel, push.size.xy))) {
        return;
    }
    imageStore(out_color, ivec2(pixel), accum[pixel.y * push.size.x + pixel.x]);
}
