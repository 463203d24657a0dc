#version 460
// ReSTIR DI, first step (src/passes/restir.rs): per G-buffer pixel, `candidates` light samples
// resampled into a reservoir (RIS); in the biased combination its sample's shadow ray then
// (visibility reuse: an occluded sample keeps its count and loses its weight); with TEMPORAL,
// the previous frame's reservoir at the point's reprojected pixel merged in where it was built
// for a similar surface, its count capped at `history_cap` times the candidates.
#extension GL_GOOGLE_include_directive : require
#include "kernel/restir_initial.glsl"
#include "pixel.glsl"

KERNEL_LOCAL_SIZE;

#include "random.glsl"
#include "gbuffer.glsl"
const bool GGX_WALTER = false;  // the BSDF is evaluated here, never sampled
#include "shading.glsl"
#include "restir.glsl"

// Where world point p was in the previous frame's grid of samples (pixel coordinates, each
// pixel's sample at +0.5: the image position less that frame's jitter), and its view depth there;
// false when it was behind that camera.
bool reproject(vec3 p, out vec2 pos, out float depth) {
    bool front = camera_project(prev_camera.origin, prev_camera.forward, prev_camera.right, prev_camera.up,
                                camera_orthographic(prev_camera.flags), p, params.size, pos, depth);
    pos -= camera_jitter(prev_camera.flags);
    return front;
}

void main() {
    ivec2 pixel = ivec2(tile_pixel());
    if (any(greaterThanEqual(uvec2(pixel), params.size))) {
        return;
    }
    uint index = uint(pixel.y) * params.size.x + uint(pixel.x);
    ShadePoint sp;
    bool lit = gbuffer_lit(pixel, sp);
    Reservoir r = reservoir_empty();
    if (lit) {
        // Resampled importance sampling of the candidates, 1/M weights.
        uint m = params.candidates;
        for (uint i = 0u; i < m; ++i) {
            vec4 u = rand4(uvec2(pixel), params.frame * m + i, RNG_RESTIR_CANDIDATE, params.seed);
            vec2 bary;
            float pdf;
            uint id = restir_candidate(u, 0.0, bary, pdf);
            if (pdf > 0.0) {
                float pick = rand4(uvec2(pixel), params.frame * m + i, RNG_RESTIR_PICK, params.seed).x;
                reservoir_add(r, id, bary, restir_target(sp, id, bary) / pdf, pick);
            }
        }
        r.m = float(m);
        vec3 wi;
        bool to_point;
        vec3 target;
        float p_hat = luminance(restir_contribution(sp, r.id, r.bary, wi, to_point, target));
        reservoir_finish(r, p_hat, r.m);
        // (Spec constants only as plain `if` conditions: naga rejects `!UNBIASED`.)
        if (UNBIASED) {
        } else {
            if (r.w > 0.0 && !restir_visible(sp, wi, to_point, target)) {
                r.w = 0.0;
            }
        }

        if (TEMPORAL) {
            vec2 pos;
            float prev_depth;
            if (params.history != 0u && reproject(sp.p, pos, prev_depth)) {
                ivec2 q = ivec2(floor(pos));
                if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(params.size)))) {
                    uint qi = uint(q.y) * params.size.x + uint(q.x);
                    Reservoir h;
                    RESERVOIR_LOAD(history, qi, h);
                    vec3 hn = oct_decode(unpackSnorm2x16(history[qi].normal));
                    float hd = history[qi].depth;
                    // The history's surface against this point as that camera saw it.
                    bool similar = h.id != RESTIR_NONE && abs(hd - prev_depth) <= 0.1 * prev_depth
                                && dot(hn, sp.n) >= 0.9;
                    if (similar) {
                        h.m = min(h.m, params.history_cap * r.m);
                        vec4 u = rand4(uvec2(pixel), params.frame, RNG_RESTIR_TEMPORAL, params.seed);
                        Reservoir c = reservoir_empty();
                        reservoir_add(c, r.id, r.bary, p_hat * r.w * r.m, u.x);
                        float h_hat = restir_target(sp, h.id, h.bary);
                        bool took_history = reservoir_add(c, h.id, h.bary, h_hat * h.w * h.m, u.y);
                        c.m = r.m + h.m;
                        float c_hat = took_history ? h_hat : p_hat;
                        float z = c.m;
                        if (UNBIASED) {
                            // 1/Z: count only the reservoirs whose domain could have produced the
                            // sample (p^ > 0 there); the history's domain is this frame's surface
                            // at its pixel (exact for a static scene and camera).
                            ShadePoint sq;
                            bool q_lit = gbuffer_lit(q, sq);
                            z = (c_hat > 0.0 ? r.m : 0.0)
                              + ((q_lit && restir_target(sq, c.id, c.bary) > 0.0) ? h.m : 0.0);
                        }
                        reservoir_finish(c, c_hat, z);
                        r = c;
                    }
                }
            }
        }
    }
    RESERVOIR_STORE(reservoirs, index, r, sp, lit, 0u);
}
