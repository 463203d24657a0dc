#version 460
// Depth-aware (bilateral) blur of an AO image over the 4x4 tile of ssao.comp's rotation pattern:
// the taps at offsets -2..1 in x and y cover each of the 16 rotations once, so on a plane the
// pattern averages away. Each tap is weighted by how close its surface lies to the centre's plane
// (distance along the centre's normal, relative to the centre's view depth: a Gaussian of sigma
// `weights.x`) and by the agreement of the normals (max(n·n0, 0)^`weights.y`), so AO does not
// bleed across silhouettes or creases. Taps without a surface are skipped; so is a pixel
// without a surface (written 1).
#extension GL_GOOGLE_include_directive : require
#include "kernel/ao_blur.glsl"

KERNEL_LOCAL_SIZE;

#include "camera.glsl"

// The view-space position (camera at the origin) of `pixel`'s surface at `depth`.
// The camera, copied out of the push constants once per invocation: its vec3 fields read from
// push-constant memory inside the loops cost llvmpipe a load each time (field by field: naga
// cannot read the OpCopyLogical a whole-struct copy compiles to).
vec3 cam_origin;
vec3 cam_forward;
vec3 cam_right;
vec3 cam_up;
bool cam_ortho;

vec3 view_position(ivec2 pixel, float depth) {
    return camera_point(vec3(0.0), cam_forward, cam_right, cam_up, cam_ortho, vec2(pixel) + 0.5, params.size, depth);
}

void main() {
    cam_origin = params.camera.origin;
    cam_forward = params.camera.forward;
    cam_right = params.camera.right;
    cam_up = params.camera.up;
    cam_ortho = params.camera.orthographic != 0u;
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
    float sum = 0.0;
    float weight = 0.0;
    for (int dy = -2; dy <= 1; ++dy) {
        for (int dx = -2; dx <= 1; ++dx) {
            ivec2 q = pixel + ivec2(dx, dy);
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) {
                continue;
            }
            float d = imageLoad(gb_depth, q).x;
            if (d <= 0.0) {
                continue;
            }
            float plane = dot(view_position(q, d) - p0, n0) * inv_sigma;
            float w = exp(-0.5 * plane * plane);
            w *= pow(max(dot(normalize(imageLoad(gb_normal, q).xyz), n0), 0.0), params.normal_exponent);
            sum += w * imageLoad(ao_in, q).x;
            weight += w;
        }
    }
    // The centre tap has weight 1, so weight > 0.
    imageStore(out_ao, pixel, vec4(sum / weight));
}
