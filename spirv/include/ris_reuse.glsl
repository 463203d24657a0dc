// Reuse for the path tracer's first-hit RIS (`--ris-reuse`, src/passes/pathtrace.rs `RisReuse`;
// the megakernel only): after its fresh candidates (path.glsl's path_ris) a pixel's first hit
// merges the first-hit reservoirs the previous sample index left, its own (RIS_TEMPORAL: the
// pixel's previous sample, another point of the pixel) and RIS_REUSE_NEIGHBOURS random pixels'
// within RIS_REUSE_RADIUS (RIS_SPATIAL), where they were built for a similar surface (distance
// from the camera within 10 %, normals within about 25 degrees), each reused sample weighed by
// its target function p^ at this pixel's hit. The combination is unbiased, by pairwise MIS
// (ris_reuse below: each stored hit's surface rebuilt, for its own target); the merged M is
// capped at RIS_REUSE_CAP times the candidates. No visibility enters the reuse: the
// kept sample gets path_ris's one shadow ray. The result is written for the next sample index
// (`ris_next`; the host swaps `ris_prev` and `ris_next` between dispatches of one sample each).
//
// Include after shading.glsl and camera.glsl, in a kernel with `params` (PathParams) and the
// `ris_prev` and `ris_next` bindings; path.glsl then calls ris_reuse (UMBRA_RIS_REUSE).
#ifndef UMBRA_RIS_REUSE_GLSL
#define UMBRA_RIS_REUSE_GLSL
#define UMBRA_RIS_REUSE

#include "gbuffer.glsl"
#include "resample.glsl"

// The reuse's random numbers: reused reservoir j (neighbour j < RIS_REUSE_NEIGHBOURS, the pixel's
// own at j = RIS_REUSE_NEIGHBOURS) draws its pixel from rng_stream(RIS_REUSE_DEPTH + j,
// RNG_RIS_CANDIDATE) and whether it is kept from rng_stream(RIS_REUSE_DEPTH + j, RNG_RIS_PICK):
// past the candidates' streams (k < DirectSampling::MAX_CANDIDATES), within the first hit's
// RIS_DEPTHS (random.glsl).
const uint RIS_REUSE_DEPTH = 256u;

// Whether the kernel reuses at all (spec constants only as plain `if` conditions).
bool ris_reuses() {
    if (RIS_TEMPORAL) {
        return true;
    }
    if (RIS_SPATIAL) {
        return true;
    }
    return false;
}

// The distance from the camera of a first hit at p (a pinhole's from the eye, an orthographic
// view's from its plane): the hit distance of the camera ray that found it.
float ris_view_distance(vec3 p) {
    vec3 d = p - params.camera.origin;
    return camera_orthographic(params.camera.flags) ? dot(d, params.camera.forward) : length(d);
}

// The shading point of a stored first hit (triangle `tri`, barycentrics `bary`, position p), as
// path_shade builds it, seen from the camera (a dispersive volume at its material's ior: its
// refracted colour is picked per path).
ShadePoint ris_stored_point(uint tri, vec2 bary, vec3 p) {
    Hit hit;
    hit.t = 0.0;
    hit.tri = tri;
    hit.bary = bary;
    ShadePoint sp;
    sp.p = p;
    sp.depth = ris_view_distance(p);
    sp.wo = camera_orthographic(params.camera.flags) ? -params.camera.forward : normalize(params.camera.origin - p);
    vec3 ng = normalize(hit_normal(hit));
    bool front = dot(ng, sp.wo) >= 0.0;
    if (!front) {
        ng = -ng;
    }
    sp.ng = ng;
    uint material = tri_material(tri);
    vec4 uv = tri_uv(tri, bary);
    sp.n = shading_normal(tri, bary, ng, uv);
    basis(sp.n, sp.t, sp.b);
    sp.wo_local = vec3(dot(sp.wo, sp.t), dot(sp.wo, sp.b), dot(sp.wo, sp.n));
    sp.material = material;
    sp.roughness = 0.0;
    sp.uv1 = vec2(0.0);
    sp.s = material_surface(material, uv);
    sp.s.base *= tri_color(tri, bary).rgb;
    if (coat_normal_differs()) {
        surface_coat_normal(sp.s, coat_normal_lod(tri, bary, ng, uv, LOD_LEVEL0), sp.t, sp.b, sp.n);
    }
    surface_anisotropy(sp.s, tri, bary, uv, LOD_LEVEL0, sp.t, sp.b, sp.n);
    if (HAS_TRANSMISSION) {
        float ior = material_vec(material, MATERIAL_PARAMS_TEXEL).y;
        sp.s.eta = front ? ior : 1.0 / ior;
    }
    return sp;
}

// Pixel `index`'s reservoir for this sample index: none (M = 0; a sample whose first hit does no
// RIS leaves it so, path_ris overwrites it otherwise).
void ris_reuse_clear(uint index) {
    ris_next[index].light = RESTIR_NONE;
    ris_next[index].weight = 0.0;
    ris_next[index].bary = vec2(0.0);
    ris_next[index].count = 0.0;
    ris_next[index].hit_tri = 0u;
    ris_next[index].hit_bary = vec2(0.0);
    ris_next[index].position = vec3(0.0);
    ris_next[index].normal = 0u;
}

// Merges with r (the fresh candidates' reservoir at sp, the canonical one: their weights' sum,
// the kept sample, M = m candidates) the previous sample index's reservoirs (this file's header)
// by pairwise MIS, finishes the result and stores it with its first hit (`hit`) for the next
// sample index. Returns the kept sample's unshadowed contribution at sp (restir_contribution's,
// with wi, to_point and target).
vec3 ris_reuse(inout Reservoir r, ShadePoint sp, Hit hit, uvec2 pixel, uint sample_index, out vec3 wi,
               out bool to_point, out vec3 target) {
    uint seed = params.seed;
    float m = r.m;
    uint index = pixel.y * params.size.x + pixel.x;
    // The canonical sample X_c: p^_c(X_c) and p^_c(X_c) W_c (= w_sum / m).
    uint c_id = r.id;
    vec2 c_bary = r.bary;
    float c_hat = restir_target(sp, c_id, c_bary);
    float c_weight = c_hat > 0.0 ? r.w_sum / m : 0.0;
    // The reservoirs taken (similar first hits): their pixels and draws.
    uint taken[RIS_REUSE_NEIGHBOURS + 1u];
    uint taken_j[RIS_REUSE_NEIGHBOURS + 1u];
    uint n_taken = 0u;
    for (uint j = 0u; j <= RIS_REUSE_NEIGHBOURS; ++j) {
        vec4 v = rand4(pixel, sample_index, rng_stream(RIS_REUSE_DEPTH + j, RNG_RIS_CANDIDATE), seed);
        ivec2 q = ivec2(pixel);
        bool use = false;
        if (j < RIS_REUSE_NEIGHBOURS) {
            if (RIS_SPATIAL) {
                // A uniform point of the disc of RIS_REUSE_RADIUS pixels.
                float radius = RIS_REUSE_RADIUS * sqrt(v.x);
                float phi = 2.0 * PI * v.y;
                q += ivec2(round(radius * vec2(cos(phi), sin(phi))));
                use = q != ivec2(pixel) && all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(params.size)));
            }
        } else {
            if (RIS_TEMPORAL) {
                use = true;
            }
        }
        if (!use) {
            continue;
        }
        uint qi = uint(q.y) * params.size.x + uint(q.x);
        if (!(ris_prev[qi].count > 0.0)) {
            continue;
        }
        vec3 hn = oct_decode(unpackSnorm2x16(ris_prev[qi].normal));
        float hd = ris_view_distance(ris_prev[qi].position);
        if (!(abs(hd - sp.depth) <= 0.1 * sp.depth && dot(hn, sp.n) >= 0.9)) {
            continue;
        }
        taken[n_taken] = qi;
        taken_j[n_taken] = j;
        ++n_taken;
    }
    // Pairwise MIS (Bitterli 2022, Lin et al. 2022's GRIS with confidence weights): each taken
    // reservoir i and the canonical one weigh their samples by the balance heuristic of the two
    // (M_i p^_i against M_c / n p^_c, p^_i the target at i's own first hit), each pair 1/n of
    // the whole; the weights then sum to 1 wherever p^_c > 0, and vanish where a reservoir's
    // own target does: W = w_sum / p^_c(y), unbiased.
    float n = float(n_taken);
    float m_c = n_taken == 0u ? 1.0 : 0.0;
    float total_m = m;
    Reservoir o = reservoir_empty();
    for (uint k = 0u; k < n_taken; ++k) {
        uint qi = taken[k];
        ShadePoint sq = ris_stored_point(ris_prev[qi].hit_tri, ris_prev[qi].hit_bary, ris_prev[qi].position);
        uint hid = ris_prev[qi].light;
        vec2 hb = ris_prev[qi].bary;
        float hm = ris_prev[qi].count;
        float own = hm * restir_target(sq, hid, hb);                // M_i p^_i(X_i)
        float here = restir_target(sp, hid, hb);                     // p^_c(X_i)
        float canon = (m / n) * here;
        float m_i = own + canon > 0.0 ? own / (own + canon) / n : 0.0;
        float pick = rand4(pixel, sample_index, rng_stream(RIS_REUSE_DEPTH + taken_j[k], RNG_RIS_PICK), seed).x;
        reservoir_add(o, hid, hb, m_i * here * ris_prev[qi].weight, pick);
        float other = hm * restir_target(sq, c_id, c_bary);          // M_i p^_i(X_c)
        float mine = (m / n) * c_hat;
        m_c += mine + other > 0.0 ? mine / (mine + other) / n : 0.0;
        total_m += hm;
    }
    float pick_c =
        rand4(pixel, sample_index, rng_stream(RIS_REUSE_DEPTH + RIS_REUSE_NEIGHBOURS + 1u, RNG_RIS_PICK), seed).x;
    reservoir_add(o, c_id, c_bary, m_c * c_weight, pick_c);
    vec3 c = restir_contribution(sp, o.id, o.bary, wi, to_point, target);
    reservoir_finish(o, luminance(c), 1.0);
    o.m = min(total_m, RIS_REUSE_CAP * m);
    r = o;
    ris_next[index].light = r.id;
    ris_next[index].weight = r.w;
    ris_next[index].bary = r.bary;
    ris_next[index].count = r.m;
    ris_next[index].hit_tri = hit.tri;
    ris_next[index].hit_bary = hit.bary;
    ris_next[index].position = sp.p;
    ris_next[index].normal = packSnorm2x16(oct_encode(sp.n));
    return c;
}

#endif
