// Light samples resampled by RIS (resampled importance sampling, Talbot et al. 2005): the
// candidates, target function and reservoirs that ReSTIR DI (restir.glsl, the hybrid's direct
// light) and the path tracer's first hit (path.glsl, `--direct ris`) share.
//
// The light samples: a point on an emissive triangle (its sampling-table entry and barycentrics:
// area measure) or a punctual light (counting measure). The target function p^ is the luminance
// of the unshadowed contribution f cos Le G at the shading point; the candidates come from the
// emissive table by power (a uniform point on the triangle) or the punctual lights' table by
// power, the two pools picked with probability restir_emissive_share().
//
// The including kernel includes shading.glsl first and has `params` with `light_count` and
// `punctual_count`.
#ifndef UMBRA_RESAMPLE_GLSL
#define UMBRA_RESAMPLE_GLSL

// A shading point: position, view depth (the G-buffer's; the hit distance in the path tracer),
// frames, the material as a BSDF surface and the viewing direction in its frame.
struct ShadePoint {
    vec3 p;
    float depth;
    vec3 ng;  // geometric normal (the G-buffer's, facing the camera)
    vec3 n;   // shading normal
    vec3 t;
    vec3 b;
    vec3 wo;  // towards the camera (world)
    vec3 wo_local;
    uint material;
    float roughness;  // perceptual
    vec2 uv1;         // the G-buffer's second UV set (lightmaps)
    Surface s;
};

// The probability that a candidate comes from the emissive triangles rather than the punctual
// lights.
float restir_emissive_share() {
    bool emissive = false;
    if (HAS_LIGHTS) {
        emissive = params.light_count > 0u;
    }
    bool punctual = false;
    if (HAS_PUNCTUAL) {
        punctual = params.punctual_count > 0u;
    }
    return emissive ? (punctual ? 0.5 : 1.0) : 0.0;
}

// The candidates' pick of a light of a pool of `count` whose power pick has probability `pmf`:
// with probability `uniform_share` a uniform pick, else by power (a defensive mixture: a light
// of little power close to a surface is picked no less often than uniform_share / count, which
// bounds its samples' weights).
float restir_pick_pmf(float pmf, uint count, float uniform_share) {
    return uniform_share / float(count) + (1.0 - uniform_share) * pmf;
}

// restir_pick_pmf's uniform pick, `k`, where u < uniform_share (u uniform in [0, 1)); else the
// number in [0, 1) for the power pick, in `rest`.
bool restir_uniform_pick(float u, uint count, float uniform_share, out uint k, out float rest) {
    k = 0u;
    rest = 0.0;
    if (u < uniform_share) {
        k = min(uint(u / uniform_share * float(count)), count - 1u);
        return true;
    }
    rest = (u - uniform_share) / (1.0 - uniform_share);
    return false;
}

// One candidate light sample from u: its id (GpuReservoir::light), barycentrics and source
// density (area measure for a triangle's point, a probability for a punctual light; 0: none);
// each pool's light by restir_pick_pmf's mixture with share `uniform_share` of uniform picks
// (0: by power alone).
uint restir_candidate(vec4 u, float uniform_share, out vec2 bary, out float pdf) {
    float share = restir_emissive_share();
    bary = vec2(0.0);
    pdf = 0.0;
    uint id = RESTIR_NONE;
    uint k;
    float rest;
    if (HAS_LIGHTS) {
        if (u.w < share) {
            if (!restir_uniform_pick(u.x, params.light_count, uniform_share, k, rest)) {
                k = pick_light(rest, params.light_count);
            }
            vec3 cdf_pmf_area = light_cdf_pmf_area(k);
            bary = sample_triangle(u.yz);
            pdf = share * restir_pick_pmf(cdf_pmf_area.y, params.light_count, uniform_share) / cdf_pmf_area.z;
            id = k;
        }
    }
    if (HAS_PUNCTUAL) {
        if (u.w >= share) {
            if (!restir_uniform_pick(u.x, params.punctual_count, uniform_share, k, rest)) {
                k = pick_punctual(rest, params.punctual_count);
            }
            pdf = (1.0 - share) * restir_pick_pmf(punctual_vec(k, 3u).z, params.punctual_count, uniform_share);
            id = RESTIR_PUNCTUAL | k;
        }
    }
    return id;
}

// Light sample (id, bary) seen from sp, unshadowed: f cos Le G (rgb; 0 where it cannot light
// the point), the direction towards it (world), and the shadow ray's end (a point, or none for a
// directional light).
vec3 restir_contribution(ShadePoint sp, uint id, vec2 bary, out vec3 wi, out bool to_point, out vec3 target) {
    vec3 li = vec3(0.0);
    wi = sp.n;
    to_point = false;
    target = sp.p;
    if (id == RESTIR_NONE) {
        return vec3(0.0);
    }
    // (A reused sample of a light the scene no longer has, after an update, lights nothing.)
    if (HAS_PUNCTUAL) {
        if ((id & RESTIR_PUNCTUAL) != 0u && (id & ~RESTIR_PUNCTUAL) < params.punctual_count) {
            li = punctual_incident(id & ~RESTIR_PUNCTUAL, sp.p, wi, to_point, target);
        }
    }
    if (HAS_LIGHTS) {
        if ((id & RESTIR_PUNCTUAL) == 0u && id < params.light_count) {
            uint ltri = light_tri(id);
            target = (1.0 - bary.x - bary.y) * tri_vertex(ltri, 0u) + bary.x * tri_vertex(ltri, 1u)
                   + bary.y * tri_vertex(ltri, 2u);
            vec3 ln = normalize(tri_normal(ltri));
            vec3 to_light = target - sp.p;
            float dist2 = dot(to_light, to_light);
            wi = to_light * inversesqrt(dist2);
            to_point = true;
            li = emitted(ltri, bary, ln, -wi) * (abs(dot(ln, wi)) / dist2);
        }
    }
    vec3 wi_local;
    if (light_side(sp.ng, sp.t, sp.b, sp.n, surface_transmits(sp.s), wi, wi_local) == 0.0) {
        return vec3(0.0);
    }
    return bsdf_eval(sp.s, sp.wo_local, wi_local) * abs(wi_local.z) * li;
}

// The target function p^ of light sample (id, bary) at sp.
float restir_target(ShadePoint sp, uint id, vec2 bary) {
    vec3 wi;
    bool to_point;
    vec3 target;
    return luminance(restir_contribution(sp, id, bary, wi, to_point, target));
}

// Whether nothing blocks the light sample's direction wi (towards `target` when to_point).
bool restir_visible(ShadePoint sp, vec3 wi, bool to_point, vec3 target) {
    vec3 wi_local;
    return light_reaches(sp.p, sp.ng, sp.t, sp.b, sp.n, surface_transmits(sp.s), wi, to_point, target, wi_local);
}

// A reservoir being built: the sample kept, the sum of the resampling weights, the candidates it
// stands for (M) and, once finished, the unbiased contribution weight W.
struct Reservoir {
    uint id;
    vec2 bary;
    float w_sum;
    float m;
    float w;
};

Reservoir reservoir_empty() {
    Reservoir r;
    r.id = RESTIR_NONE;
    r.bary = vec2(0.0);
    r.w_sum = 0.0;
    r.m = 0.0;
    r.w = 0.0;
    return r;
}

// Streams one candidate of resampling weight `weight` into r, kept with probability weight /
// the new sum (u uniform in [0, 1)); true when it was kept.
bool reservoir_add(inout Reservoir r, uint id, vec2 bary, float weight, float u) {
    if (!(weight > 0.0)) {
        return false;
    }
    r.w_sum += weight;
    if (u * r.w_sum < weight) {
        r.id = id;
        r.bary = bary;
        return true;
    }
    return false;
}

// Finishes r: W = w_sum / (z p^(y)), z the candidate count the weights are normalised by (1/M
// weights: z = M), 0 when the kept sample's target is 0.
void reservoir_finish(inout Reservoir r, float target, float z) {
    r.w = (target > 0.0 && z > 0.0) ? r.w_sum / (z * target) : 0.0;
    if (!(r.w > 0.0)) {
        r.w = 0.0;
    }
}

#endif
