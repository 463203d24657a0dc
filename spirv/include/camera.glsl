// The pinhole camera (src/render.rs camera_params): a unit view direction through the image
// position `pos` in pixels (pixel centres at +0.5), row 0 at the top.
#ifndef UMBRA_CAMERA_GLSL
#define UMBRA_CAMERA_GLSL

vec3 camera_ray(vec3 forward, vec3 right, vec3 up, vec2 pos, uvec2 size) {
    vec2 ndc = vec2(2.0 * pos.x / float(size.x) - 1.0, 1.0 - 2.0 * pos.y / float(size.y));
    return normalize(forward + ndc.x * right + ndc.y * up);
}

#endif
