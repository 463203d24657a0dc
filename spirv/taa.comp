#version 460
// Temporal anti-aliasing (Karis 2014, "High quality temporal supersampling"; Yang, Liu and Salvi
// 2020's survey) and the running mean of still sub-frames (src/passes/taa.rs).
//
// Each frame samples every pixel at its centre moved by the camera's jitter; the resolve blends
// that sample with the history, which holds a value per pixel centre:
// - accumulate (TAA_ACCUMULATE): the camera is still, so the history is read at the pixel and the
//   blend is the running mean (weight 1/n for the n-th sub-frame): N sub-frames give the mean of
//   N jittered samples exactly, a box filter over the pixel as the path tracer's;
// - reproject: the point the pixel's centre sees (at the depth its sample found, moved back by
//   the G-buffer's motion where the geometry moved, TAA_MOTION; the environment by its
//   direction) is projected into the previous camera and the history read there
//   (bilinear, or a Catmull-Rom spline with TAA_CATMULL_ROM); it is clipped to the box of the
//   frame's 3x3 neighbourhood (mean ± clip_sigma × standard deviation, Salvi 2016, intersected
//   with the neighbours' min-max; in YCoCg), and blended with weight max(1/n, blend) for the
//   frame. Both colours are blended as c / (1 + luma) (Karis), so that a bright sample does not
//   dominate the mean of its neighbours.
#extension GL_GOOGLE_include_directive : require
#include "kernel/taa.glsl"
#include "camera.glsl"

KERNEL_LOCAL_SIZE;

float luma(vec3 c) {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

// Karis' tonemapped space for the blend, and its inverse.
vec3 compress(vec3 c) {
    return c / (1.0 + luma(c));
}

vec3 expand(vec3 c) {
    return c / max(1.0 - luma(c), 1e-6);
}

vec3 to_ycocg(vec3 c) {
    return vec3(dot(c, vec3(0.25, 0.5, 0.25)), dot(c, vec3(0.5, 0.0, -0.5)), dot(c, vec3(-0.25, 0.5, -0.25)));
}

vec3 from_ycocg(vec3 c) {
    return vec3(c.x + c.y - c.z, c.x + c.z, c.x - c.y - c.z);
}

// The frame's radiance, finite and non-negative (a NaN or infinite sample must not enter the
// history, where it would stay).
vec3 current_at(ivec2 pixel) {
    vec3 c = imageLoad(current, pixel).rgb;
    return any(isnan(c)) || any(isinf(c)) ? vec3(0.0) : max(c, vec3(0.0));
}

// The Catmull-Rom spline's weights of the texels at -1, 0, 1, 2 for a point t (0 to 1) past texel
// 0: they sum to 1, and the outer two are negative.
vec4 catmull_rom_weights(float t) {
    float t2 = t * t;
    return vec4(t * (-0.5 + t * (1.0 - 0.5 * t)), 1.0 + t2 * (-2.5 + 1.5 * t), t * (0.5 + t * (2.0 - 1.5 * t)),
                t2 * (-0.5 + 0.5 * t));
}

// h moved toward the box's centre until it lies within it (Playdead's clip, INSIDE 2016).
vec3 clip_to_box(vec3 h, vec3 lo, vec3 hi) {
    vec3 centre = 0.5 * (lo + hi);
    vec3 extent = 0.5 * (hi - lo) + 1e-7;
    vec3 v = h - centre;
    vec3 a = abs(v / extent);
    float m = max(a.x, max(a.y, a.z));
    return m > 1.0 ? centre + v / m : h;
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(params.size);
    if (any(greaterThanEqual(pixel, size))) {
        return;
    }
    vec3 c = current_at(pixel);
    if ((params.flags & TAA_HISTORY) == 0u) {
        imageStore(resolved, pixel, vec4(c, 1.0));
        return;
    }
    if ((params.flags & TAA_ACCUMULATE) != 0u) {
        vec4 h = imageLoad(history, pixel);
        float n = h.a + 1.0;
        imageStore(resolved, pixel, vec4(h.rgb + (c - h.rgb) / n, n));
        return;
    }

    // The point the pixel's centre sees, and where it lay in the previous frame's image.
    vec3 eye = params.camera.origin;
    vec3 forward = params.camera.forward;
    bool ortho = camera_orthographic(params.camera.flags);
    vec3 origin;
    vec3 dir;
    camera_ray(eye, forward, params.camera.right, params.camera.up, ortho, vec2(pixel) + 0.5, params.size, origin,
               dir);
    float depth = imageLoad(gb_depth, pixel).x;
    bool prev_ortho = camera_orthographic(prev_camera.flags);
    // The environment: by its direction (a pinhole sees it at infinity), or along the ray.
    vec3 p = depth > 0.0 ? origin + dir * (depth / dot(dir, forward))
                         : (prev_ortho ? origin : prev_camera.origin + dir);
    // Moved geometry (TAA_MOTION): the surface point where it lay in the previous frame.
    if ((params.flags & TAA_MOTION) != 0u && depth > 0.0) {
        p -= imageLoad(gb_motion, pixel).xyz;
    }
    vec2 pos;
    float prev_depth;
    bool front = camera_project(prev_camera.origin, prev_camera.forward, prev_camera.right, prev_camera.up,
                                prev_ortho, p, params.size, pos, prev_depth);

    // The history there, bilinear over the texels inside the image; its colour by a Catmull-Rom
    // spline over the 4x4 texels around it where they all lie inside (TAA_CATMULL_ROM), each
    // texel compressed as the blend is. The history's length stays the bilinear one.
    vec4 h = vec4(0.0);
    float weight = 0.0;
    if (front) {
        vec2 f = pos - 0.5;
        ivec2 base = ivec2(floor(f));
        vec2 t = f - vec2(base);
        for (int k = 0; k < 4; ++k) {
            ivec2 q = base + ivec2(k & 1, k >> 1);
            float w = ((k & 1) != 0 ? t.x : 1.0 - t.x) * ((k >> 1) != 0 ? t.y : 1.0 - t.y);
            if (w > 0.0 && all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, size))) {
                vec4 texel = imageLoad(history, q);
                h += w * vec4(compress(texel.rgb), texel.a);
                weight += w;
            }
        }
        if ((params.flags & TAA_CATMULL_ROM) != 0u && all(greaterThanEqual(base, ivec2(1)))
            && all(lessThan(base + 2, size))) {
            vec4 wx = catmull_rom_weights(t.x);
            vec4 wy = catmull_rom_weights(t.y);
            vec3 spline = vec3(0.0);
            for (int j = 0; j < 4; ++j) {
                vec3 row = vec3(0.0);
                for (int i = 0; i < 4; ++i) {
                    row += wx[i] * compress(imageLoad(history, base + ivec2(i - 1, j - 1)).rgb);
                }
                spline += wy[j] * row;
            }
            // All four bilinear texels lie inside: weight is 1.
            h.rgb = spline * weight;
        }
    }
    vec3 cc = compress(c);
    if (weight < 1e-3) {
        // Nothing of it was in view: the pixel starts afresh.
        imageStore(resolved, pixel, vec4(c, 1.0));
        return;
    }
    h /= weight;

    // The neighbourhood's box.
    vec3 m1 = vec3(0.0);
    vec3 m2 = vec3(0.0);
    vec3 lo = vec3(1e30);
    vec3 hi = vec3(-1e30);
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 q = clamp(pixel + ivec2(dx, dy), ivec2(0), size - 1);
            vec3 s = to_ycocg(compress(current_at(q)));
            m1 += s;
            m2 += s * s;
            lo = min(lo, s);
            hi = max(hi, s);
        }
    }
    m1 /= 9.0;
    vec3 sigma = sqrt(max(m2 / 9.0 - m1 * m1, vec3(0.0)));
    vec3 box_lo = max(lo, m1 - params.clip_sigma * sigma);
    vec3 box_hi = min(hi, m1 + params.clip_sigma * sigma);
    vec3 clipped = from_ycocg(clip_to_box(to_ycocg(h.rgb), box_lo, box_hi));

    float n = h.a + 1.0;
    float alpha = max(1.0 / n, params.blend);
    vec3 blended = mix(clipped, cc, alpha);
    imageStore(resolved, pixel, vec4(expand(blended), min(n, 1.0 / max(params.blend, 1e-6))));
}
