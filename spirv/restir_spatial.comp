#version 460
// ReSTIR DI, spatial reuse (src/passes/restir.rs): each pixel's reservoir merged with those of
// `neighbours` pixels picked at random within `radius` pixels whose surfaces are similar (view
// depth within 10 %, normals within about 25 degrees), each neighbour's sample weighed by its
// target function here. The result is the frame's reservoir, which the lighting pass shades and
// the next frame's temporal step reuses.
#extension GL_GOOGLE_include_directive : require
#include "kernel/restir_spatial.glsl"
#include "pixel.glsl"

KERNEL_LOCAL_SIZE;

#include "random.glsl"
#include "gbuffer.glsl"
const bool GGX_WALTER = false;  // the BSDF is evaluated here, never sampled
#include "shading.glsl"
#include "restir.glsl"

// Most neighbours a pixel takes (RestirSettings::MAX_NEIGHBOURS).
const uint MAX_NEIGHBOURS = 8u;

void main() {
    ivec2 pixel = ivec2(tile_pixel());
    if (any(greaterThanEqual(uvec2(pixel), params.size))) {
        return;
    }
    uint index = uint(pixel.y) * params.size.x + uint(pixel.x);
    ShadePoint sp;
    bool lit = gbuffer_lit(pixel, sp);
    Reservoir c = reservoir_empty();
    uint flags = 0u;
    if (lit) {
        Reservoir r;
        RESERVOIR_LOAD(reservoirs_in, index, r);
        float r_hat = restir_target(sp, r.id, r.bary);
        float u = rand4(uvec2(pixel), params.frame, RNG_RESTIR_SPATIAL, params.seed).w;
        reservoir_add(c, r.id, r.bary, r_hat * r.w * r.m, u);
        c.m = r.m;
        float c_hat = r_hat;
        // The neighbours taken and their counts (for the unbiased combination's 1/Z).
        ivec2 taken[MAX_NEIGHBOURS];
        float taken_m[MAX_NEIGHBOURS];
        uint n_taken = 0u;
        for (uint k = 0u; k < min(params.neighbours, MAX_NEIGHBOURS); ++k) {
            vec4 v = rand4(uvec2(pixel), params.frame * MAX_NEIGHBOURS + k, RNG_RESTIR_SPATIAL, params.seed);
            // A uniform point of the disc of `radius` pixels.
            float radius = params.radius * sqrt(v.x);
            float phi = 2.0 * PI * v.y;
            ivec2 q = pixel + ivec2(round(radius * vec2(cos(phi), sin(phi))));
            if (q == pixel || any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(params.size)))) {
                continue;
            }
            ShadePoint sq;
            if (!gbuffer_lit(q, sq) || !restir_similar(sp, sq.depth, sq.n)) {
                continue;
            }
            uint qi = uint(q.y) * params.size.x + uint(q.x);
            Reservoir h;
            RESERVOIR_LOAD(reservoirs_in, qi, h);
            if (h.id == RESTIR_NONE) {
                continue;
            }
            float h_hat = restir_target(sp, h.id, h.bary);
            if (reservoir_add(c, h.id, h.bary, h_hat * h.w * h.m, v.z)) {
                c_hat = h_hat;
            }
            c.m += h.m;
            taken[n_taken] = q;
            taken_m[n_taken] = h.m;
            ++n_taken;
        }
        float z = c.m;
        if (UNBIASED) {
            // 1/Z: only the reservoirs whose pixel could have produced the kept sample count.
            z = c_hat > 0.0 ? r.m : 0.0;
            for (uint k = 0u; k < n_taken; ++k) {
                ShadePoint sq;
                gbuffer_point(taken[k], sq);
                if (restir_target(sq, c.id, c.bary) > 0.0) {
                    z += taken_m[k];
                }
            }
        }
        reservoir_finish(c, c_hat, z);
        c.m = min(c.m, params.history_cap * float(params.candidates));
        if (UNBIASED) {
        } else {
            // The kept sample's visibility here, folded into its weight: the lighting pass then
            // traces no ray, and an occluded sample, weight 0, is not reused by the next frame
            // (else samples occluded here but not where they came from would keep returning).
            vec3 wi;
            bool to_point;
            vec3 target;
            restir_contribution(sp, c.id, c.bary, wi, to_point, target);
            if (c.w > 0.0 && !restir_visible(sp, wi, to_point, target)) {
                c.w = 0.0;
            }
            flags = RESTIR_VISIBLE;
        }
    }
    RESERVOIR_STORE(reservoirs_out, index, c, sp, lit, flags);
}
