// The camera (src/gpu/layout.rs GpuCamera, src/render.rs): a pinhole, whose rays leave `eye`, or
// an orthographic view, whose rays run parallel to `forward` from the plane through `eye`
// (`right` and `up` then the view's half extents). Image positions are in pixels (pixel centres
// at +0.5), row 0 at the top; view depth is measured along `forward` (unit) from `eye`.
#ifndef UMBRA_CAMERA_GLSL
#define UMBRA_CAMERA_GLSL

// GpuCamera.flags: whether the camera is orthographic (else a pinhole). (Its bit and the jitter's
// unit are layout.glsl's CAMERA_ORTHOGRAPHIC and CAMERA_JITTER_UNIT, written out: hosts include
// this file through gbuffer.glsl without layout.glsl.)
bool camera_orthographic(uint flags) {
    return (flags & 1u) != 0u;
}

// GpuCamera.flags: the offset of every pixel's sample position from its centre (anti-aliasing's
// jitter), pixels: two signed 12-bit counts of 1/4096 pixel, bits 8..20 (x) and 20..32 (y).
vec2 camera_jitter(uint flags) {
    return vec2(bitfieldExtract(int(flags), 8, 12), bitfieldExtract(int(flags), 20, 12)) * (1.0 / 4096.0);
}

// The image position pixel `pixel` samples: its centre, moved by the jitter of the camera's
// `flags` (exactly the centre where there is none).
vec2 camera_sample(ivec2 pixel, uint flags) {
    return vec2(pixel) + 0.5 + camera_jitter(flags);
}

// The offset of image position `pos` across the image plane at unit view depth (a pinhole's) or
// from the plane's centre (an orthographic view's).
vec3 camera_offset(vec3 right, vec3 up, vec2 pos, uvec2 size) {
    vec2 ndc = vec2(2.0 * pos.x / float(size.x) - 1.0, 1.0 - 2.0 * pos.y / float(size.y));
    return ndc.x * right + ndc.y * up;
}

// The point at view depth `depth` on the ray of image-plane offset `offset` (camera_offset),
// relative to `eye`: camera_point without normalising the ray (the same point to rounding, for
// kernels that reconstruct many).
vec3 camera_depth_point(vec3 forward, bool orthographic, vec3 offset, float depth) {
    return orthographic ? offset + depth * forward : depth * (forward + offset);
}

// The ray through image position `pos`: its origin and unit direction.
void camera_ray(vec3 eye, vec3 forward, vec3 right, vec3 up, bool orthographic, vec2 pos, uvec2 size,
                out vec3 origin, out vec3 dir) {
    vec3 offset = camera_offset(right, up, pos, size);
    origin = orthographic ? eye + offset : eye;
    dir = orthographic ? forward : normalize(forward + offset);
}

// The world point at view depth `depth` on the ray through image position `pos`.
vec3 camera_point(vec3 eye, vec3 forward, vec3 right, vec3 up, bool orthographic, vec2 pos, uvec2 size,
                  float depth) {
    vec3 origin;
    vec3 dir;
    camera_ray(eye, forward, right, up, orthographic, pos, size, origin, dir);
    return origin + dir * (depth / dot(dir, forward));
}

// Where world point `p` lies in the image and its view depth; false when it is behind the camera
// (depth <= 0; `pos` is then meaningless).
bool camera_project(vec3 eye, vec3 forward, vec3 right, vec3 up, bool orthographic, vec3 p, uvec2 size,
                    out vec2 pos, out float depth) {
    vec3 d = p - eye;
    depth = dot(d, forward);
    vec2 ndc = vec2(dot(d, right) / dot(right, right), dot(d, up) / dot(up, up));
    ndc /= orthographic ? 1.0 : max(depth, 1e-30);
    pos = vec2((ndc.x + 1.0) * 0.5 * float(size.x), (1.0 - ndc.y) * 0.5 * float(size.y));
    return depth > 0.0;
}

#endif
