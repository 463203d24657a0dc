#version 460
// Ray-traced ambient occlusion over a G-buffer: the ground truth ssao.comp approximates.
//
// AO(p) = (1/π) ∫ V_r(p, ω) cos θ dω: the cosine-weighted fraction of the hemisphere around the
// shading normal whose rays leave p without meeting geometry within the radius r. `samples`
// cosine-distributed rays per pixel (random numbers from (pixel, frame * rays + i, seed)), each an
// any-hit query through the BVH over (0, r) from the origin offset off the geometric surface as
// shadow rays are (shading.glsl). A direction below the geometric surface counts as occluded (the
// surface itself blocks it). The output is the fraction of unoccluded rays, an unbiased estimate
// of AO(p) with variance AO(1 − AO) / rays. Pixels without a surface get 1. Alpha-masked and
// blended surfaces occlude as the path tracer sees them (shading.glsl's alpha test).
#extension GL_GOOGLE_include_directive : require
#include "kernel/rtao.glsl"
#include "pixel.glsl"

KERNEL_LOCAL_SIZE;

const bool BECKMANN = false;
const bool GGX_WALTER = false;

#include "random.glsl"
#include "sampling.glsl"
#include "gbuffer.glsl"
#include "shading.glsl"

void main() {
    ivec2 pixel = ivec2(tile_pixel());
    uvec2 size = params.size;
    if (any(greaterThanEqual(uvec2(pixel), size))) {
        return;
    }
    float depth = imageLoad(gb_depth, pixel).x;
    // Rays [first, first + batch) of the pixel's `rays` (`first_ray`, `batch_rays`): one dispatch per
    // batch, each adding its rays' share, so no invocation runs long enough for llvmpipe's loop
    // limiter (65,535 loop iterations per invocation, then every loop breaks) to cut it short.
    uint rays = max(params.samples, 1u);
    uint first = params.first_ray;
    uint last = min(first + max(params.batch_rays, 1u), rays);
    if (depth <= 0.0) {
        imageStore(out_ao, pixel, vec4(1.0));
        return;
    }
    vec3 p = gbuffer_position(params.camera.origin, params.camera.forward, params.camera.right, params.camera.up,
                              camera_orthographic(params.camera.flags), camera_jitter(params.camera.flags), pixel, size,
                              depth);
    vec3 n = normalize(imageLoad(gb_normal, pixel).xyz);
    vec3 ng = oct_decode(unpackSnorm2x16(imageLoad(gb_material, pixel).y));
    vec3 o = offset_ray(p, ng);
    float radius = params.radius;
    vec3 t;
    vec3 b;
    basis(n, t, b);
    uint open = 0u;
    for (uint i = first; i < last; ++i) {
        vec2 u = rand4(uvec2(pixel), params.frame * rays + i, 0u, params.seed).xy;
        vec3 w = sample_cosine_hemisphere(u);
        vec3 dir = w.x * t + w.y * b + w.z * n;
        if (dot(dir, ng) > 0.0 && !bvh_any(o, dir, 0.0, radius)) {
            open += 1u;
        }
    }
    float before = first > 0u ? imageLoad(out_ao, pixel).x : 0.0;
    imageStore(out_ao, pixel, vec4(before + float(open) / float(rays)));
}
