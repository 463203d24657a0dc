#version 460
// Depth-aware (bilateral) blur of an AO image over the 4x4 tile of the screen-space kernels'
// pattern (ao_noise.glsl): the taps at offsets -2..1 in x and y cover each of the 16 rotations
// once, so on a plane the pattern averages away. Each tap is weighted by how close its surface
// lies to the centre's plane (distance along the centre's normal, relative to the centre's view
// depth: a Gaussian of sigma `depth_sigma`) and by the agreement of the normals
// (max(n·n0, 0)^8), so AO does not bleed across silhouettes or creases. Taps without a surface
// are skipped; so is a pixel without a surface (written 1). A tap's position is its view ray
// scaled to its depth (no normalisation), the 8th power three squarings: on lavapipe the blur
// cost as much as GTAO itself with a normalised ray and pow() per tap.
//
// With `scale` 2 the AO read is half-resolution AO (gtao.comp: texel t computed at pixel 2t), and
// the blur is also its depth-aware upsample: each pixel weighs the 4x4 AO texels nearest to it by
// their pixels' surfaces against its own. Where none of them lies on its surface (a feature
// thinner than the AO's texels), it takes their plain mean.
#extension GL_GOOGLE_include_directive : require
#include "kernel/ao_blur.glsl"

KERNEL_LOCAL_SIZE;

#include "camera.glsl"

// The camera, copied out of the push constants once per invocation: its vec3 fields read from
// push-constant memory inside the loops cost llvmpipe a load each time (field by field: naga
// cannot read the OpCopyLogical a whole-struct copy compiles to).
vec3 cam_forward;
vec3 cam_right;
vec3 cam_up;
bool cam_ortho;
vec2 cam_jitter;

// The view-space position (camera at the origin) of `pixel`'s surface at view depth `depth`.
vec3 view_position(ivec2 pixel, float depth) {
    return camera_depth_point(cam_forward, cam_ortho, camera_offset(cam_right, cam_up, vec2(pixel) + 0.5 + cam_jitter, params.size),
                              depth);
}

void main() {
    cam_forward = params.camera.forward;
    cam_right = params.camera.right;
    cam_up = params.camera.up;
    cam_ortho = camera_orthographic(params.camera.flags);
    cam_jitter = camera_jitter(params.camera.flags);
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(params.size);
    if (any(greaterThanEqual(pixel, size))) {
        return;
    }
    float d0 = imageLoad(gb_depth, pixel).x;
    if (d0 <= 0.0) {
        imageStore(out_ao, pixel, vec4(1.0));
        return;
    }
    vec3 p0 = view_position(pixel, d0);
    vec3 n0 = normalize(imageLoad(gb_normal, pixel).xyz);
    float inv_sigma = 1.0 / (params.depth_sigma * d0);
    int scale = int(max(params.scale, 1u));
    ivec2 ao_size = (size + scale - 1) / scale;
    // The first of the 4x4 AO texels: at full resolution offsets -2..1 about the pixel.
    ivec2 first = (2 * pixel + scale) / (2 * scale) - 2;
    float sum = 0.0;
    float weight = 0.0;
    float plain = 0.0;
    float taps = 0.0;
    for (int dy = 0; dy < 4; ++dy) {
        for (int dx = 0; dx < 4; ++dx) {
            ivec2 t = first + ivec2(dx, dy);
            if (any(lessThan(t, ivec2(0))) || any(greaterThanEqual(t, ao_size))) {
                continue;
            }
            ivec2 q = t * scale;
            float d = imageLoad(gb_depth, q).x;
            if (d <= 0.0) {
                continue;
            }
            float plane = dot(view_position(q, d) - p0, n0) * inv_sigma;
            float w = exp(-0.5 * plane * plane);
            float c = max(dot(normalize(imageLoad(gb_normal, q).xyz), n0), 0.0);
            c *= c;
            c *= c;
            w *= c * c;
            float ao = imageLoad(ao_in, t).x;
            sum += w * ao;
            weight += w;
            plain += ao;
            taps += 1.0;
        }
    }
    // At full resolution the centre tap has weight 1, so weight > 0.
    float result = weight > 0.0 ? sum / weight : (taps > 0.0 ? plain / taps : 1.0);
    imageStore(out_ao, pixel, vec4(result));
}
