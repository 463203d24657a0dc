#version 460
// Screen-space ambient occlusion over a G-buffer (src/passes/ao.rs documents the estimator).
//
// AO(p) = cosine-weighted fraction of the hemisphere around the normal whose rays leave p
// without meeting geometry within the radius r: the quantity rtao.comp estimates with rays.
// SSAO estimates it from the depth buffer alone: `samples` directions of a fixed cosine-weighted
// kernel (stratified in cos²θ, golden-ratio azimuths), rotated about the normal per pixel by a
// 4x4 tiled (Bayer) pattern that ao_blur.comp averages away. Along each direction, `steps`
// points at distances r·f², f = (s + j) / (steps - 1 + j) (so more points near p, the last at r).
// A point is occluded when it lies behind the surface seen at its pixel (the depth buffer read as
// the front of solid matter, tested against that surface's plane, so a point above the same tilted
// plane is not self-occluded by pixel quantisation), unless that surface is more than r in front
// of p (the range check). Points that project off screen, behind the camera, or onto a pixel
// without a surface are unoccluded: the screen holds no information there.
#extension GL_GOOGLE_include_directive : require
#include "kernel/ssao.glsl"

KERNEL_LOCAL_SIZE;

#include "random.glsl"
#include "sampling.glsl"
#include "gbuffer.glsl"
#include "ao_noise.glsl"

// The camera, copied out of the push constants once per invocation: its vec3 fields read from
// push-constant memory inside the loops cost llvmpipe a load each time (field by field: naga
// cannot read the OpCopyLogical a whole-struct copy compiles to).
vec3 cam_origin;
vec3 cam_forward;
vec3 cam_right;
vec3 cam_up;
bool cam_ortho;
vec2 cam_jitter;

const float GOLDEN = 0.61803398874989485;

vec3 position_at(ivec2 pixel, float depth) {
    return gbuffer_position(cam_origin, cam_forward, cam_right, cam_up, cam_ortho, cam_jitter, pixel, params.size, depth);
}

// Whether point q (world) is behind the depth buffer's surface, within range of p at depth d0.
bool occluded(vec3 q, float d0, float radius, float bias) {
    vec2 pos;
    float dq;
    if (!camera_project(cam_origin, cam_forward, cam_right, cam_up, cam_ortho, q, params.size, pos, dq)) {
        return false;
    }
    // In the pixels' sample grid (each pixel's sample at its centre moved by the jitter).
    pos -= cam_jitter;
    vec2 size = vec2(params.size);
    if (any(lessThan(pos, vec2(0.0))) || any(greaterThanEqual(pos, size))) {
        return false;
    }
    ivec2 pixel = ivec2(pos);
    float ds = imageLoad(gb_depth, pixel).x;
    if (ds <= 0.0 || d0 - ds > radius) {
        return false;
    }
    vec3 s = position_at(pixel, ds);
    vec3 ns = normalize(imageLoad(gb_normal, pixel).xyz);
    return dot(q - s, ns) < -bias;
}

void main() {
    cam_origin = params.camera.origin;
    cam_forward = params.camera.forward;
    cam_right = params.camera.right;
    cam_up = params.camera.up;
    cam_ortho = camera_orthographic(params.camera.flags);
    cam_jitter = camera_jitter(params.camera.flags);
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    uvec2 size = params.size;
    if (any(greaterThanEqual(uvec2(pixel), size))) {
        return;
    }
    float d0 = imageLoad(gb_depth, pixel).x;
    if (d0 <= 0.0) {
        imageStore(out_ao, pixel, vec4(1.0));
        return;
    }
    vec3 p = position_at(pixel, d0);
    vec3 n = normalize(imageLoad(gb_normal, pixel).xyz);
    float radius = params.radius;
    // The bias grows with depth: float error of reconstructed positions.
    float bias = params.bias + 1e-5 * d0;
    uint directions = max(params.samples, 1u);
    uint steps = max(params.steps, 1u);

    // The tile's rotation about n, and its offset within each cos²θ stratum.
    float k = ao_tile_noise(pixel);
    vec4 kernel_seed = rand4(uvec2(0u), params.frame, 0u, params.seed);
    vec3 t;
    vec3 b;
    basis(n, t, b);

    uint hidden = 0u;
    for (uint i = 0u; i < directions; ++i) {
        vec2 u = vec2((float(i) + k) / float(directions), fract(kernel_seed.x + float(i) * GOLDEN + k));
        vec3 w = sample_cosine_hemisphere(u);
        vec3 dir = w.x * t + w.y * b + w.z * n;
        float j = fract(kernel_seed.y + float(i) * GOLDEN * GOLDEN + k * 7.0);
        for (uint s = 0u; s < steps; ++s) {
            float f = steps == 1u ? 1.0 : (float(s) + j) / (float(steps - 1u) + j);
            if (occluded(p + dir * (radius * f * f), d0, radius, bias)) {
                hidden += 1u;
                break;
            }
        }
    }
    imageStore(out_ao, pixel, vec4(1.0 - float(hidden) / float(directions)));
}
