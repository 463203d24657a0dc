#version 460
// Ground-truth-based ambient occlusion (Jimenez, Wu, Pesce and Jarabo 2016, "Practical Real-Time
// Strategies for Accurate Indirect Occlusion"), with the sampling of Intel's XeGTAO (2021):
// the quantity rtao.comp estimates with rays (src/passes/ao.rs), from the depth buffer read as a
// height field seen from the camera.
//
// The hemisphere around the normal is cut into `samples` slices: planes through the view vector
// v, each holding a screen direction. In a slice, the cosine-weighted visible arc between the two
// horizons h0 < h1 (angles from v, positive towards the slice's screen direction) has a closed
// form; weighted by the length of the normal's projection onto the slice and averaged over the
// slices it is the cosine-weighted visible fraction of the hemisphere, exactly, where the
// occluders are a height field (Jimenez et al., eqs. 3 to 10). The few slices' average is divided
// by the same average for an open hemisphere, so a surface nothing occludes gets exactly 1. Each horizon is the highest of
// `steps` depth-buffer points on its side of the pixel, at screen distances s r (s stratified in
// (0, 1]; XeGTAO's s² measured less accurate against RTAO's hard radius, src/passes/ao.rs),
// whose pull fades over the last `falloff` fraction of r (the range check: an occluder beyond r
// does not count; 0, the default, cuts off at r, and then a point beyond r no more than r in
// front of p stands for the solid behind it, which may come within r). Points off screen or on
// the background do not
// raise the horizon (the screen holds no information there, as for SSAO), nor do points within
// `bias` of the tangent plane (they cannot raise it, and their rounding would).
//
// The slices' angle and the steps' offsets vary over each 4x4 tile of AO texels (ao_noise.glsl)
// and with the frame; ao_blur.comp averages the tile. With `scale` 2 (half resolution) each AO
// texel is computed at the G-buffer pixel 2 × its coordinates and ao_blur.comp upsamples. Not
// taken from XeGTAO: its radius multiplier (1.457) and final power (2.2), artistic choices that
// would depart from the definition RTAO computes, and its depth MIP chain (a GPU cache
// optimisation).
#extension GL_GOOGLE_include_directive : require
#include "kernel/gtao.glsl"

KERNEL_LOCAL_SIZE;

#include "random.glsl"
#include "sampling.glsl"
#include "gbuffer.glsl"
#include "ao_noise.glsl"

// The camera, copied out of the push constants once per invocation (as in ssao.comp).
vec3 cam_origin;
vec3 cam_forward;
vec3 cam_right;
vec3 cam_up;
bool cam_ortho;
vec2 cam_jitter;

const float GOLDEN = 0.61803398874989485;
// The nearest point of a side is at least this many pixels from the pixel (XeGTAO's 1.3).
const float MIN_OFFSET_PX = 1.3;

// The cosine-weighted visible arc of a slice between the normal's angle n and horizon h
// (Jimenez et al. eq. 7, one side).
float arc(float h, float n, float cos_n, float sin_n) {
    return 0.25 * (cos_n + 2.0 * h * sin_n - cos(2.0 * h - n));
}

void main() {
    cam_origin = params.camera.origin;
    cam_forward = params.camera.forward;
    cam_right = params.camera.right;
    cam_up = params.camera.up;
    cam_ortho = camera_orthographic(params.camera.flags);
    cam_jitter = camera_jitter(params.camera.flags);
    ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
    uvec2 size = params.size;
    uint scale = max(params.scale, 1u);
    if (any(greaterThanEqual(uvec2(texel), (size + scale - 1u) / scale))) {
        return;
    }
    ivec2 pixel = texel * int(scale);
    float d0 = imageLoad(gb_depth, pixel).x;
    if (d0 <= 0.0) {
        imageStore(out_ao, texel, vec4(1.0));
        return;
    }
    // Positions by camera_depth_point, the samples' as the pixel's (their differences matter).
    vec3 p = cam_origin + camera_depth_point(cam_forward, cam_ortho, camera_offset(cam_right, cam_up, vec2(pixel) + 0.5 + cam_jitter, size), d0);
    vec3 n = normalize(imageLoad(gb_normal, pixel).xyz);
    vec3 v = cam_ortho ? -cam_forward : normalize(cam_origin - p);
    float radius = params.radius;
    // Pixels per world unit across the image plane at p's depth, along x and y (a pinhole's
    // half extents grow with depth).
    float at_depth = cam_ortho ? 1.0 : d0;
    vec2 px_per_unit = vec2(size) / (2.0 * at_depth * vec2(length(cam_right), length(cam_up)));
    vec3 screen_x = normalize(cam_right);
    vec3 screen_y = -normalize(cam_up);
    // Occluder weight: 1 up to (1 - falloff) r, 0 from r on.
    float fade = params.falloff * radius;
    // The bias grows with depth: float error of reconstructed positions (as in ssao.comp).
    float bias = params.bias + 1e-5 * d0;

    uint slices = max(params.samples, 1u);
    uint steps = max(params.steps, 1u);
    float k = ao_tile_noise(texel);
    vec4 kernel_seed = rand4(uvec2(0u), params.frame, 0u, params.seed);
    float slice_noise = fract(kernel_seed.x + k);
    float step_noise = fract(kernel_seed.y + k * 7.0);
    ivec2 isize = ivec2(size);
    float visibility = 0.0;
    float open = 0.0;
    for (uint i = 0u; i < slices; ++i) {
        float phi = PI * (float(i) + slice_noise) / float(slices);
        vec2 omega = vec2(cos(phi), sin(phi));
        // The slice's screen direction in the world, and its plane's frame: v and the direction
        // made orthogonal to v.
        vec3 dir = omega.x * screen_x + omega.y * screen_y;
        vec3 ortho_dir = dir - dot(dir, v) * v;
        vec3 axis = normalize(cross(ortho_dir, v));
        vec3 projected = n - axis * dot(n, axis);
        float projected_length = length(projected);
        if (!(projected_length > 1e-6)) {
            continue;
        }
        float cos_n = clamp(dot(projected, v) / projected_length, 0.0, 1.0);
        float angle_n = (dot(ortho_dir, projected) < 0.0 ? -1.0 : 1.0) * acos(cos_n);
        float sin_n = sin(angle_n);
        // The horizons start at the tangent plane (cosines from v); side 0 is +omega.
        float low0 = cos(angle_n + 0.5 * PI);
        float low1 = cos(angle_n - 0.5 * PI);
        float horizon0 = low0;
        float horizon1 = low1;
        // The slice's radius in pixels; the nearest step clears the pixel itself.
        vec2 reach = radius * omega * px_per_unit;
        float min_s = MIN_OFFSET_PX / max(length(reach), 1e-6);
        for (uint j = 0u; j < steps; ++j) {
            float s = (float(j) + fract(step_noise + float(i + j * slices) * GOLDEN)) / float(steps);
            s += min_s;
            ivec2 offset = ivec2(round(s * reach));
            for (int side = 0; side < 2; ++side) {
                ivec2 q = side == 0 ? pixel + offset : pixel - offset;
                if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, isize))) {
                    continue;
                }
                float dq = imageLoad(gb_depth, q).x;
                if (dq <= 0.0) {
                    continue;
                }
                vec3 offset = camera_offset(cam_right, cam_up, vec2(q) + 0.5 + cam_jitter, size);
                vec3 delta = cam_origin + camera_depth_point(cam_forward, cam_ortho, offset, dq) - p;
                float dist = length(delta);
                vec3 u = cam_ortho ? cam_forward : normalize(cam_forward + offset);
                float b = dot(delta, u);
                float disc = b * b - (dist * dist - radius * radius);
                bool inside = dist < radius;
                bool enters = disc >= 0.0 && b < 0.0 && d0 - dq <= radius;
                vec3 moved = delta + (-b - sqrt(max(disc, 0.0))) * u;
                float weight;
                if (fade > 0.0) {
                    weight = clamp((radius - dist) / fade, 0.0, 1.0);
                } else {
                    weight = (inside || enters) ? 1.0 : 0.0;
                    delta = inside ? delta : moved;
                    dist = inside ? dist : length(moved);
                }
                weight = dot(delta, n) > bias ? weight : 0.0;
                float low = side == 0 ? low0 : low1;
                float h = mix(low, dot(delta, v) / dist, weight);
                if (side == 0) {
                    horizon0 = max(horizon0, h);
                } else {
                    horizon1 = max(horizon1, h);
                }
            }
        }
        // The horizons' angles, within a quarter turn of the normal (the hemisphere's edge).
        float h0 = -acos(clamp(horizon1, -1.0, 1.0));
        float h1 = acos(clamp(horizon0, -1.0, 1.0));
        h0 = angle_n + clamp(h0 - angle_n, -0.5 * PI, 0.5 * PI);
        h1 = angle_n + clamp(h1 - angle_n, -0.5 * PI, 0.5 * PI);
        visibility += projected_length * (arc(h0, angle_n, cos_n, sin_n) + arc(h1, angle_n, cos_n, sin_n));
        // The same slice unoccluded (horizons at n ± pi/2): cos n + n sin n.
        open += projected_length * (cos_n + angle_n * sin_n);
    }
    // Over all slice angles the unoccluded weights average to 1; over a few they do not, and the
    // ratio keeps an open hemisphere at exactly 1 (a ratio estimator, with the same limit).
    imageStore(out_ao, texel, vec4(open > 0.0 ? clamp(visibility / open, 0.0, 1.0) : 1.0));
}
