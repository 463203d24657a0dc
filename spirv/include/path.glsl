// One path's step of the path tracer, shared by its two integrators: the megakernel
// (pathtrace.comp: a lane traces its pixel's paths start to end) and the wavefront path tracer
// (wavefront.comp: each step a kernel of its own over a queue of paths, Laine, Karras and Aila
// 2013). A step is the closest hit of the path's ray (the caller's), then path_shade: emission,
// light samples, the next ray. The kernel that includes this file defines
//     void path_shadow(inout Path path, vec3 origin, vec3 d, float tmax, vec3 c, uint bit)
// which adds c (a light sample's contribution, NONFINITE_* bit `bit`) to path.radiance when
// nothing blocks the shadow ray origin + t d, t < tmax: traced at once in the megakernel, queued
// for a kernel of shadow rays in the wavefront. Include after random.glsl, camera.glsl,
// environment.glsl and shading.glsl, with `params` a push-constant block holding PathParams'
// fields but the camera, and the path tracers' accumulation bindings (`accum`, `moment`, the
// `aov_*` buffers, `aov_specular` and `aov_split` among them, `stats`) and the specialisation
// constants SPLIT_LOBES and RIS.
#ifndef UMBRA_PATH_GLSL
#define UMBRA_PATH_GLSL

#include "resample.glsl"

// Which strategies find the emitters (LIGHT_SAMPLING and BSDF_HITS, never both false: `Strategy`
// in src/passes/pathtrace.rs): light sampling (next-event estimation of the emissive triangles
// and the environment map) and BSDF sampling (emission that a BSDF-sampled ray hits); MIS weighs
// them where both run. Under every strategy, punctual lights (delta lights: no ray hits them) are
// found by light sampling only, and emission that light sampling cannot find (a constant
// environment, the map with env_nee off, any light-sampling density of 0) by BSDF sampling only.
// Camera rays see emitters always. (Specialization constants are only ever tested here, never
// negated or combined with one another: naga's SPIR-V reader rejects the constant such an
// expression makes, OpSpecConstantOp.)

float mis_weight(float a, float b) {
    if (POWER_HEURISTIC) {
        a *= a;
        b *= b;
    }
    return a / (a + b);
}

// The weight of emission that BSDF sampling found (density a) against light sampling (density
// b): MIS, 1 without light sampling, and with light sampling alone 0 wherever it could have found
// it. UNWEIGHTED_BSDF_HITS (the `testing` feature's deliberately biased variant) leaves MIS out:
// such emission counts fully, on top of light sampling's weighted share.
float bsdf_hit_weight(float a, float b) {
    if (LIGHT_SAMPLING) {
        if (BSDF_HITS) {
            if (UNWEIGHTED_BSDF_HITS) {
                return 1.0;
            }
            return mis_weight(a, b);
        }
        return b > 0.0 ? 0.0 : 1.0;
    }
    return 1.0;
}

// The weight of a light sample (density a) against BSDF sampling (density b): MIS, or 1 with
// light sampling alone.
float light_sample_weight(float a, float b) {
    return BSDF_HITS ? mis_weight(a, b) : 1.0;
}

// Non-finite sources (PathStats.nonfinite_sources bits): the stages whose contribution (or, for
// BSDF sampling, weight and pdf) was NaN or Inf.
const uint NONFINITE_ENVIRONMENT = 1u;
const uint NONFINITE_EMISSION = 2u;
const uint NONFINITE_EMISSIVE_NEE = 4u;
const uint NONFINITE_PUNCTUAL = 8u;
const uint NONFINITE_ENV_NEE = 16u;
const uint NONFINITE_BSDF_SAMPLE = 32u;
const uint NONFINITE_RIS = 64u;

uint nonfinite_bit(vec3 v, uint bit) {
    return (any(isnan(v)) || any(isinf(v))) ? bit : 0u;
}

// One path: its ray, what it has gathered so far and what it carries.
struct Path {
    vec3 origin;
    vec3 dir;
    vec3 radiance;
    vec3 throughput;
    float prev_pdf;  // solid-angle pdf of the BSDF sample that made this ray; 0 for the camera
    uint depth;      // scattering events so far
    uint nonfinite;  // NONFINITE_* bits of the stages that produced a non-finite value
    // KHR_materials_dispersion: 0 until the path meets a dispersive volume; then the colour
    // channel + 1 it follows from there on (the throughput 0 in the others).
    uint channel;
    // SPLIT_LOBES only (the denoiser's lobe split): the part of `radiance` that left the first
    // hit through its specular lobes (reflection, transmission, sheen, coat: all but the
    // diffuse one), the share of what the path gathers beyond the first hit that does (per
    // channel, f_specular / f at the first hit's sampled direction), and the first hit's
    // metallic (0 for a miss), which with its base colour makes the divisor of that part
    // (specular_albedo).
    vec3 specular;
    vec3 share;
    float metallic;
};

// Defined by the kernel (this file's header): adds c to path.radiance, and c_spec, its
// specular part, to path.specular (SPLIT_LOBES), when the shadow ray origin + t d, t in
// [0, tmax), is unblocked.
void path_shadow(inout Path path, vec3 origin, vec3 d, float tmax, vec3 c, vec3 c_spec, uint bit);

// The specular part of c, gathered beyond the first hit (SPLIT_LOBES; else 0).
vec3 specular_part(Path path, vec3 c) {
    if (SPLIT_LOBES) {
        return c * path.share;
    }
    return vec3(0.0);
}

// The numbers of sample `sample_index` of `pixel` for `stream` (random.glsl): low-discrepancy
// (qmc4, whose pairs are (y, z) and (x, w): a use's 2D sample sits in y and z) unless the render
// asks for independent ones (LOW_DISCREPANCY, a specialization constant: PathOptions::sampler).
vec4 path_rand4(uvec2 pixel, uint sample_index, uint stream, uint seed) {
    if (LOW_DISCREPANCY) {
        return qmc4(pixel, sample_index, stream, seed);
    }
    return rand4(pixel, sample_index, stream, seed);
}

// Sample `sample_index` of `pixel` (of the whole image) through `camera`: its camera ray.
Path camera_path(vec3 eye, vec3 forward, vec3 right, vec3 up, bool orthographic, uvec2 image_size, uvec2 pixel,
                 uint sample_index) {
    vec4 jitter = path_rand4(pixel, sample_index, rng_stream(0u, RNG_CAMERA), params.seed);
    Path path;
    camera_ray(eye, forward, right, up, orthographic, vec2(pixel) + jitter.yz, image_size, path.origin, path.dir);
    path.radiance = vec3(0.0);
    path.throughput = vec3(1.0);
    path.prev_pdf = 0.0;
    path.depth = 0u;
    path.nonfinite = 0u;
    path.channel = 0u;
    path.specular = vec3(0.0);
    path.share = vec3(0.0);
    path.metallic = 0.0;
    return path;
}

// The specular share of f = bsdf_eval(s, wo, wi), per channel: (f − the diffuse lobe's) / f
// (1 where f is 0: no diffuse lobe then).
vec3 specular_share(Surface s, vec3 wo, vec3 wi, vec3 f) {
    vec3 d = bsdf_eval_diffuse(s, wo, wi);
    return mix(vec3(1.0), clamp((f - d) / f, 0.0, 1.0), greaterThan(f, vec3(0.0)));
}

// The specular part of a light sample's contribution c (through f = bsdf_eval(s, wo, wi)):
// at the first hit by the lobes' shares of f, beyond it by the path's share (SPLIT_LOBES; else 0).
vec3 first_specular(Path path, Surface s, vec3 wo, vec3 wi, vec3 f, vec3 c) {
    if (SPLIT_LOBES) {
        return c * (path.depth == 0u ? specular_share(s, wo, wi, f) : path.share);
    }
    return vec3(0.0);
}

// The share of the path tracer's RIS candidates that pick their light uniformly within its pool
// (restir_candidate's defensive mixture; the rest by power).
const float RIS_FLAT = 0.5;

// The density, in solid angle towards a point on an emissive triangle (its power pick `pmf`,
// its `area`; the point at squared distance dist2, its normal at cosine cos_light with the
// direction), that stands for RIS's in the MIS between RIS and BSDF sampling: m times the
// candidates' source density (the share of emissive candidates, restir_candidate's pick of the
// triangle with RIS_FLAT, a uniform point on it). Any weights that sum to one across the two
// strategies keep the sum unbiased, and a deterministic one keeps RIS's estimate of its weighted
// part unbiased (RIS's own density of a point is not known in closed form).
float ris_emissive_pdf(float pmf, float area, float dist2, float cos_light, uint m) {
    float pick = restir_pick_pmf(pmf, params.light_count, RIS_FLAT);
    return float(m) * restir_emissive_share() * (pick / area) * dist2 / max(cos_light, 1e-8);
}

// RIS's MIS weight for its kept sample `id` seen along wi (world) / wi_local from sp: against BSDF
// sampling for an emissive point, 1 for a punctual light (a delta: BSDF sampling cannot find it).
float ris_emissive_weight(ShadePoint sp, uint id, vec3 wi, vec3 wi_local, vec3 target, uint m) {
    if (HAS_LIGHTS) {
        if ((id & RESTIR_PUNCTUAL) == 0u && id < params.light_count) {
            uint ltri = light_tri(id);
            vec3 cdf_pmf_area = light_cdf_pmf_area(id);
            vec3 d = target - sp.p;
            float cos_light = abs(dot(normalize(tri_normal(ltri)), wi));
            float p = ris_emissive_pdf(cdf_pmf_area.y, cdf_pmf_area.z, dot(d, d), cos_light, m);
            return light_sample_weight(p, bsdf_pdf(sp.s, sp.wo_local, wi_local));
        }
    }
    return 1.0;
}

// The direct light at a vertex (bounce `depth`) from the emissive triangles and punctual lights
// by RIS (resample.glsl, the candidates and target of the hybrid's ReSTIR): params.ris_candidates
// candidates resampled into one by p^ = the luminance of the unshadowed f cos Le G, its shadow
// ray through path_shadow, its contribution f Le G V W with W = w_sum / (M p^(y)), an emissive
// point's weighted by MIS against BSDF sampling (ris_emissive_weight). Unbiased: p^ is positive
// wherever f Le G is (a luminance of non-negative colours), and the candidates' densities cover
// every emitter light sampling covers.
//
// With reuse (ris_reuse.glsl, included by the megakernel where RIS_TEMPORAL or RIS_SPATIAL may
// be on) the first hit's reservoir then merges the previous sample index's reservoirs and W comes
// from their unbiased combination; `hit` (the closest hit, after parallax mapping) is stored with
// it. Deeper vertices do not reuse.
void path_ris(inout Path path, ShadePoint sp, Hit hit, vec3 throughput, uvec2 pixel, uint sample_index, uint depth) {
    uint seed = params.seed;
    uint m = params.ris_candidates;
    Reservoir r = reservoir_empty();
    for (uint k = 0u; k < m; ++k) {
        vec4 u = path_rand4(pixel, sample_index, rng_stream(ris_depth(depth) + k, RNG_RIS_CANDIDATE), seed);
        vec2 bary;
        float pdf;
        uint id = restir_candidate(u, RIS_FLAT, bary, pdf);
        if (pdf > 0.0) {
            float pick = path_rand4(pixel, sample_index, rng_stream(ris_depth(depth) + k, RNG_RIS_PICK), seed).x;
            reservoir_add(r, id, bary, restir_target(sp, id, bary) / pdf, pick);
        }
    }
    vec3 wi;
    bool to_point;
    vec3 target;
    vec3 c;
    bool reused = false;
#ifdef UMBRA_RIS_REUSE
    if (ris_reuses() && depth == 0u) {
        r.m = float(m);
        c = ris_reuse(r, sp, hit, pixel, sample_index, wi, to_point, target);
        reused = true;
    }
#endif
    if (!reused) {
        c = restir_contribution(sp, r.id, r.bary, wi, to_point, target);
        reservoir_finish(r, luminance(c), float(m));
    }
    vec3 wi_local;
    float side = light_side(sp.ng, sp.t, sp.b, sp.n, surface_transmits(sp.s), wi, wi_local);
    if (r.w > 0.0 && side != 0.0) {
        c *= throughput * r.w * ris_emissive_weight(sp, r.id, wi, wi_local, target, m);
        vec3 c_spec = vec3(0.0);
        if (SPLIT_LOBES) {
            c_spec = first_specular(path, sp.s, sp.wo_local, wi_local, bsdf_eval(sp.s, sp.wo_local, wi_local), c);
        }
        vec3 o = offset_ray(sp.p, side * sp.ng);
        path_shadow(path, o, to_point ? target - o : wi, to_point ? 0.9999 : BVH_INF, c, c_spec, NONFINITE_RIS);
    }
}

// Adds what `path`'s ray finds at its end (`found`: its closest hit `hit`; else it left the
// scene): emission, direct light (through path_shadow); then samples the next ray. False when the
// path ends there. At the first hit (or miss) it records the base colour and normal into `albedo`
// and `normal_depth`, and the radiance emitted there (or the environment's) into `emitted_first`:
// the part of the sample that the denoiser must not filter.
bool path_shade(inout Path path, bool found, Hit hit, uvec2 pixel, uint sample_index, inout vec4 albedo,
                inout vec4 normal_depth, inout vec3 emitted_first) {
    uint seed = params.seed;
    uint depth = path.depth;
    vec3 dir = path.dir;
    vec3 throughput = path.throughput;
    if (!found) {
        if (HAS_ENV_MAP) {
            float w = 1.0;
            // The texel's radiance and density in one read.
            vec4 texel = env_value(env_texel(env_uv(dir), params.env_size));
            // (The map's next-event estimation is on where it is picked at all.)
            if (params.env_pick > 0.0 && path.prev_pdf > 0.0) {
                w = bsdf_hit_weight(path.prev_pdf, env_direction_pdf(texel.w, dir) * params.env_pick);
            }
            vec3 c = throughput * texel.rgb * params.env * w;
            path.radiance += c;
            path.specular += specular_part(path, c);
            path.nonfinite |= nonfinite_bit(c, NONFINITE_ENVIRONMENT);
            if (depth == 0u) {
                emitted_first = c;
            }
        } else {
            path.radiance += throughput * params.env;
            path.specular += specular_part(path, throughput * params.env);
            if (depth == 0u) {
                emitted_first = params.env;
            }
        }
        return false;
    }
    uint tri = hit.tri;
    vec3 ng = hit_normal(hit);
    float area = 0.5 * length(ng);
    ng = normalize(ng);
    vec3 wo = -dir;
    vec3 p = path.origin + hit.t * dir;
    uint material = tri_material(tri);
    // Parallax occlusion mapping: the hit's attributes are read where the ray meets the material's
    // height field, whose self-shadowing then applies to every light sample (light_side).
    hit.bary = parallax_occlusion(tri, hit.bary, wo);
    if (scene_transmits() && dot(ng, wo) < 0.0 && material_flag(material, MATERIAL_VOLUME)) {
        // A volume's boundary reached from behind: the segment ran inside it (a closed mesh
        // whose normals face out, as KHR_materials_volume requires), so Beer-Lambert.
        throughput *= exp(-material_attenuation(material) * hit.t);
    }

    // Emission, weighted against the light-sampling strategy that could have found it.
    vec4 uv = tri_uv(tri, hit.bary);
    vec3 le = emitted(tri, hit.bary, ng, wo);
    if (any(greaterThan(le, vec3(0.0)))) {
        float w = 1.0;
        if (HAS_LIGHTS && path.prev_pdf > 0.0) {
            float emissive = emissive_pdf(tri, area, path.origin, hit.t, ng, wo);
            w = bsdf_hit_weight(path.prev_pdf, emissive * (1.0 - params.env_pick));
            if (RIS) {
                // Reached from a vertex whose RIS covered every emissive triangle of the table:
                // weighed against RIS's stand-in density (ris_emissive_weight's).
                if (emissive > 0.0) {
                    float ris = ris_emissive_pdf(tri_light_pmf(tri), area, hit.t * hit.t, abs(dot(ng, wo)),
                                                 params.ris_candidates);
                    w = bsdf_hit_weight(path.prev_pdf, ris);
                }
            }
        }
        vec3 c = throughput * le * w;
        path.radiance += c;
        path.specular += specular_part(path, c);
        path.nonfinite |= nonfinite_bit(c, NONFINITE_EMISSION);
        if (depth == 0u) {
            emitted_first = c;
        }
    }

    // Shading frame: interpolated, normal-mapped normal, on the same side as the viewer.
    bool front = dot(ng, wo) >= 0.0;
    if (!front) {
        ng = -ng;
    }
    vec3 n = shading_normal(tri, hit.bary, ng, uv);
    vec3 t;
    vec3 b;
    basis(n, t, b);
    vec3 wo_local = vec3(dot(wo, t), dot(wo, b), dot(wo, n));
    Surface s = material_surface(material, uv);
    s.base *= tri_color(tri, hit.bary).rgb;
    if (coat_normal_differs()) {
        surface_coat_normal(s, coat_normal_lod(tri, hit.bary, ng, uv, LOD_LEVEL0), t, b, n);
    }
    surface_anisotropy(s, tri, hit.bary, uv, LOD_LEVEL0, t, b, n);
    if (HAS_TRANSMISSION) {
        // A refracting boundary: glass (ior) behind the front face, air behind the back.
        float ior = material_vec(material, MATERIAL_PARAMS_TEXEL).y;
        if (HAS_DISPERSION) {
            // A dispersive volume refracts each wavelength its own way: the path follows one
            // colour channel from the first such surface it meets, picked uniformly, its
            // throughput 3x on that channel and 0 on the others (an unbiased estimate of each
            // channel's own path), the channel's index of refraction from there on.
            float dispersion = material_dispersion(material);
            if (dispersion > 0.0 && s.transmission > 0.0) {
                if (path.channel == 0u) {
                    float u = path_rand4(pixel, sample_index, rng_stream(depth, RNG_DISPERSION), seed).x;
                    path.channel = 1u + min(uint(u * 3.0), 2u);
                    throughput *= 3.0 * vec3(equal(uvec3(path.channel), uvec3(1u, 2u, 3u)));
                }
                ior = dispersed_ior(ior, dispersion, path.channel - 1u);
            }
        }
        s.eta = front ? ior : 1.0 / ior;
    }
    if (depth == 0u) {
        albedo = vec4(s.base, 1.0);
        normal_depth = vec4(n, hit.t);
        if (SPLIT_LOBES) {
            path.metallic = s.metallic;
        }
    }
    // KHR_materials_unlit, modelled as an emitter of its base colour that scatters nothing: the
    // path ends here, and no light sampling finds it (BSDF-sampled rays alone, weight 1).
    if (material_unlit(material)) {
        path.radiance += throughput * s.base;
        path.specular += specular_part(path, throughput * s.base);
        if (depth == 0u) {
            emitted_first += s.base;
        }
        return false;
    }
    if (depth >= params.max_bounces || wo_local.z <= 0.0) {
        return false;
    }

    // RIS (`ris`): at every vertex its one resampled sample of the emissive triangles and
    // punctual lights stands for both of them (path_ris); the environment map keeps the
    // next-event estimation below.
    bool ris_here = false;
    if (RIS) {
        ShadePoint sp;
        sp.p = p;
        sp.depth = hit.t;
        sp.ng = ng;
        sp.n = n;
        sp.t = t;
        sp.b = b;
        sp.wo = wo;
        sp.wo_local = wo_local;
        sp.material = material;
        sp.roughness = 0.0;
        sp.uv1 = vec2(0.0);
        sp.s = s;
        path_ris(path, sp, hit, throughput, pixel, sample_index, depth);
        ris_here = true;
    }

    // Next-event estimation: one light sample and its shadow ray, from the emissive triangles
    // (one by power, a uniform point on it) or the environment map (importance-sampled by
    // luminance x sin(theta)), the map picked with probability params.env_pick (1 or 0 where the
    // scene has one of them; by their power where it has both), weighted by MIS. (Under RIS only
    // the map's share: an emissive pick samples nothing.)
    bool tri_nee = false;
    if (HAS_LIGHTS) {
        tri_nee = params.light_count > 0u && !ris_here;
    }
    bool env_nee = false;
    if (HAS_ENV_MAP) {
        env_nee = params.env_pick > 0.0;
    }
    if (LIGHT_SAMPLING) {
        if (tri_nee || env_nee) {
            vec4 u = path_rand4(pixel, sample_index, rng_stream(depth, RNG_EMISSIVE_NEE), seed);
            // With sample reuse the map or the emitters are picked by u.y, whose share, stretched
            // back, is the chosen light's first number (the pair (u.y, u.z) then stratifies each
            // light's samples: bsdf.glsl); otherwise by u.w, the map's sample from a stream of
            // its own.
            bool pick_env = (SAMPLE_REUSE ? u.y : u.w) < params.env_pick;
            if (SAMPLE_REUSE) {
                u.y = pick_env ? stretch(u.y, 0.0, params.env_pick)
                               : stretch(u.y, params.env_pick, 1.0 - params.env_pick);
            }
            vec3 wi = vec3(0.0, 0.0, 1.0);
            vec3 target = vec3(0.0);
            vec3 l_in = vec3(0.0);  // the sampled light's radiance towards p
            float pdf = 0.0;
            bool sampled = false;
            // Only the kernels of scenes with the light kind compile its sampling: llvmpipe
            // runs an if-body for every lane whichever lanes take it.
            if (HAS_ENV_MAP) {
                if (pick_env) {
                    // env_sample's 2D point is (x, z), its alias tables' keep tests y and w.
                    vec4 ue = SAMPLE_REUSE ? u.yxzw : path_rand4(pixel, sample_index, rng_stream(depth, RNG_ENV_NEE), seed).yxzw;
                    wi = env_sample(ue, params.env_size, pdf, l_in);
                    l_in *= params.env;
                    pdf *= params.env_pick;
                    sampled = pdf > 0.0;
                }
            }
            if (HAS_LIGHTS) {
                if (!pick_env && tri_nee) {
                    sampled = emissive_point(p, u.xyz, params.light_count, wi, target, l_in, pdf);
                    pdf *= 1.0 - params.env_pick;
                }
            }
            // The sample's contribution if nothing blocks it, its shadow ray traced by
            // path_shadow: from the side light can arrive from (light_side), to just short of the
            // point on a triangle or unbounded towards the map.
            vec3 wi_local;
            float side = light_side(ng, t, b, n, surface_transmits(s), wi, wi_local);
            if (sampled && side != 0.0) {
                vec3 f = bsdf_eval(s, wo_local, wi_local);
                float w = light_sample_weight(pdf, bsdf_pdf(s, wo_local, wi_local));
                vec3 c = throughput * f * abs(wi_local.z) * l_in * (w / pdf);
                vec3 c_spec = first_specular(path, s, wo_local, wi_local, f, c);
                vec3 o = offset_ray(p, side * ng);
                path_shadow(path, o, pick_env ? wi : target - o, pick_env ? BVH_INF : 0.9999, c, c_spec,
                            pick_env ? NONFINITE_ENV_NEE : NONFINITE_EMISSIVE_NEE);
            }
        }
    }

    // Punctual lights: delta distributions, so light sampling is the only strategy (no MIS); one
    // shadow ray per light evaluated (all of them up to PUNCTUAL_ALL, else PUNCTUAL_ALL picked by
    // power, stratified by u: punctual_direct's estimator, each light's term added on its own).
    if (HAS_PUNCTUAL) {
        float u = path_rand4(pixel, sample_index, rng_stream(depth, RNG_PUNCTUAL), seed).x;
        uint count = ris_here ? 0u : params.punctual_count;
        for (uint j = 0u; j < min(count, PUNCTUAL_ALL); ++j) {
            float weight;
            uint k = punctual_evaluated(j, count, u, weight);
            vec3 wi;
            bool to_point;
            vec3 position;
            vec3 li = punctual_incident(k, p, wi, to_point, position);
            vec3 wi_local;
            float side = light_side(ng, t, b, n, surface_transmits(s), wi, wi_local);
            if (any(greaterThan(li, vec3(0.0))) && side != 0.0) {
                vec3 f = bsdf_eval(s, wo_local, wi_local);
                vec3 c = throughput * (weight * f * abs(wi_local.z) * li);
                vec3 c_spec = first_specular(path, s, wo_local, wi_local, f, c);
                vec3 o = offset_ray(p, side * ng);
                path_shadow(path, o, to_point ? position - o : wi, to_point ? 0.9999 : BVH_INF, c, c_spec,
                            NONFINITE_PUNCTUAL);
            }
        }
    }

    // Continue the path by sampling the BSDF.
    vec4 u = path_rand4(pixel, sample_index, rng_stream(depth, RNG_BSDF), seed);
    vec3 wi_local;
    vec3 weight;
    float pdf;
    if (!bsdf_sample(s, wo_local, u.xyz, wi_local, weight, pdf)) {
        return false;
    }
    vec3 wi = wi_local.x * t + wi_local.y * b + wi_local.z * n;
    bool transmitted = wi_local.z < 0.0;
    float side = dot(wi, ng);
    if (transmitted ? side >= 0.0 : side <= 0.0) {
        return false;  // the shading normal and the geometry disagree about the side
    }
    if (HAS_PARALLAX) {
        // A sampled direction into the height field: the path ends (the field's interreflection
        // is not traced), so BSDF sampling sees the self-shadowing light sampling sees and MIS
        // weighs like with like.
        if (!parallax_lit(wi)) {
            return false;
        }
    }
    path.nonfinite |= nonfinite_bit(weight * float(pdf), NONFINITE_BSDF_SAMPLE);
    if (SPLIT_LOBES) {
        if (depth == 0u) {
            path.share = specular_share(s, wo_local, wi_local, bsdf_eval(s, wo_local, wi_local));
        }
    }
    throughput *= weight;
    // Light sampling covers both sides of a transmitting surface, so an emitter or the
    // environment reached either way is weighed by MIS against it.
    path.prev_pdf = pdf;
    if (depth + 1u >= params.rr_depth) {
        float q = clamp(max3(throughput), 0.05, 1.0);
        if (u.w >= q) {
            return false;
        }
        throughput /= q;
    }
    path.throughput = throughput;
    path.origin = offset_ray(p, transmitted ? -ng : ng);
    path.dir = wi;
    path.depth = depth + 1u;
    return true;
}

// A finished sample's radiance for the running mean: itself when finite; else 0, and its
// first-hit emission too, the sample counted with the stages (NONFINITE_* bits) that made it so.
void finite_sample(inout vec3 radiance, inout vec3 emitted_first, uint nonfinite) {
    if (any(isnan(radiance)) || any(isinf(radiance))) {
        atomicAdd(stats.nonfinite_samples, 1u);
        atomicOr(stats.nonfinite_sources, nonfinite);
        radiance = vec3(0.0);
        emitted_first = vec3(0.0);
    }
}

// A running mean over n_samples samples after `count` more whose sum is `sum` (`mean`: over the
// n_samples − count before them).
vec4 fold_mean(vec4 mean, vec4 sum, uint count, float n_samples) {
    return mean + (sum - float(count) * mean) / n_samples;
}

// Folds `count` more samples of pixel `index` into the running means: the sums of their
// radiance, its square, the first hit's albedo and emission; the first hit's normal and distance
// kept from the render's first sample (the host clears the buffers, alpha 0, to start one).
// Returns whether the render starts with them (`fresh`: the other running means of the pixel
// start from 0), and their new count in `n_samples`.
bool accumulate_samples(uint index, uint count, vec3 sum, vec3 sum2, vec4 sum_albedo, vec3 sum_emitted,
                        vec4 first_normal_depth, out float n_samples) {
    vec4 mean = accum[index];
    bool fresh = mean.a == 0.0;
    n_samples = mean.a + float(count);
    vec4 m2 = moment[index];
    accum[index] = vec4(mean.rgb + (sum - float(count) * mean.rgb) / n_samples, n_samples);
    moment[index] = vec4(m2.rgb + (sum2 - float(count) * m2.rgb) / n_samples, 0.0);
    aov_albedo[index] = fold_mean(fresh ? vec4(0.0) : aov_albedo[index], sum_albedo, count, n_samples);
    vec3 mean_emitted = fresh ? vec3(0.0) : aov_emission[index].rgb;
    aov_emission[index] = vec4(mean_emitted + (sum_emitted - float(count) * mean_emitted) / n_samples, 0.0);
    if (fresh) {
        aov_normal_depth[index] = first_normal_depth;
    }
    return fresh;
}

// The first hit's specular albedo, the divisor of the lobe split's specular part: 1 for a
// dielectric or a miss (`albedo`, the first hit's base colour, alpha 0), the base colour for a
// metal (`metallic`, the first hit's).
vec3 specular_albedo(vec4 albedo, float metallic) {
    return albedo.a > 0.0 ? mix(vec3(1.0), albedo.rgb, metallic) : vec3(1.0);
}

// Folds a finished sample (`radiance`, finite_sample's; `specular`, its specular part as the path
// gathered it; `emitted_first`, `albedo` and `metallic`, its first hit's) into the lobe split's
// sums: its specular part and that part's divisor (specular_albedo) into `sum_specular` (rgb) and
// `sum_split` (rgb); the luminance squared of the diffuse part (radiance less the first hit's
// emission and the specular part) over the first hit's base colour into sum_specular.a, and of
// the specular part over its divisor into sum_split.a: the denoiser's variances of the two.
void split_sample(vec3 specular, float metallic, vec3 radiance, vec3 emitted_first, vec4 albedo,
                  inout vec4 sum_specular, inout vec4 sum_split) {
    if (radiance == vec3(0.0)) {
        specular = vec3(0.0);
    }
    vec3 spec_albedo = specular_albedo(albedo, metallic);
    vec3 diffuse_albedo = albedo.a > 0.0 ? max(albedo.rgb, vec3(DENOISE_MIN_ALBEDO)) : vec3(1.0);
    float d = luminance((radiance - emitted_first - specular) / diffuse_albedo);
    float l = luminance(specular / max(spec_albedo, vec3(DENOISE_MIN_ALBEDO)));
    sum_specular += vec4(specular, d * d);
    sum_split += vec4(spec_albedo, l * l);
}

// Folds the lobe split's sums of `count` more samples of pixel `index` (split_sample's) into
// its running means in aov_specular and aov_split (accumulate_samples' `fresh` and `n_samples`).
void accumulate_split(uint index, uint count, vec4 sum_specular, vec4 sum_split, bool fresh, float n_samples) {
    aov_specular[index] = fold_mean(fresh ? vec4(0.0) : aov_specular[index], sum_specular, count, n_samples);
    aov_split[index] = fold_mean(fresh ? vec4(0.0) : aov_split[index], sum_split, count, n_samples);
}

// The sums of one pixel's finished samples in a dispatch, both path tracers' (fold_sample).
struct SampleSums {
    vec3 radiance;   // of the finite samples
    vec3 radiance2;  // of their squares
    vec4 albedo;     // of the first hits' base colours
    vec3 emitted;    // of the first hits' emission
    // SPLIT_LOBES: split_sample's sums of the specular part and its divisor, and of the
    // luminances squared of the two parts divided by their divisors.
    vec4 specular;
    vec4 split;
};

SampleSums no_samples() {
    return SampleSums(vec3(0.0), vec3(0.0), vec4(0.0), vec3(0.0), vec4(0.0), vec4(0.0));
}

// Folds a finished sample into `sums`: its radiance (finite_sample's), its first hit's base
// colour and emission, and (SPLIT_LOBES) its specular part and the first hit's metalness
// (split_sample's).
void fold_sample(inout SampleSums sums, vec3 radiance, vec3 emitted_first, uint nonfinite, vec4 albedo,
                 vec3 specular, float metallic) {
    finite_sample(radiance, emitted_first, nonfinite);
    if (SPLIT_LOBES) {
        split_sample(specular, metallic, radiance, emitted_first, albedo, sums.specular, sums.split);
    }
    sums.radiance += radiance;
    sums.radiance2 += radiance * radiance;
    sums.albedo += albedo;
    sums.emitted += emitted_first;
}

// Folds `count` more samples of pixel `index` (their `sums`; the render's first sample's first
// hit `first_normal_depth`) into its running means (accumulate_samples, accumulate_split).
void accumulate_sums(uint index, uint count, SampleSums sums, vec4 first_normal_depth) {
    float n_samples;
    bool fresh = accumulate_samples(index, count, sums.radiance, sums.radiance2, sums.albedo, sums.emitted,
                                    first_normal_depth, n_samples);
    if (SPLIT_LOBES) {
        accumulate_split(index, count, sums.specular, sums.split, fresh, n_samples);
    }
}

// Adds n to a 64-bit count of the counters (`stats`) kept in two words, `lo` and `hi`: an add
// that wraps the low word carries one into the high word. A macro, since a buffer's member is
// no function argument in GLSL.
#define PATH_ADD_COUNT(lo, hi, n)            \
    {                                        \
        uint n_ = (n);                       \
        uint old_ = atomicAdd(lo, n_);       \
        if (old_ + n_ < old_) {              \
            atomicAdd(hi, 1u);               \
        }                                    \
    }

// Adds n path segments to the counters' segment count; one call per workgroup.
void count_segments(uint n) {
    PATH_ADD_COUNT(stats.segments_lo, stats.segments_hi, n);
}

// The implicit-shape marches this invocation cut short, into the counters.
void count_marches() {
    if (HAS_IMPLICIT) {
        if (implicit_marches_exhausted > 0u) {
            atomicAdd(stats.marches_exhausted, implicit_marches_exhausted);
        }
    }
}

#endif
