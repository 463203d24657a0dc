#version 460
// Progressive path tracer: one sample per pixel per dispatch, accumulated as a running mean with
// its second moment. Next-event estimation on emissive triangles, BSDF sampling, multiple
// importance sampling (power or balance heuristic), Russian roulette; or, for comparison, either
// strategy alone (LIGHT_SAMPLING, BSDF_HITS). Materials' occlusion maps (glTF occlusionTexture)
// are not read: the paths trace the occlusion they stand in for (the hybrid renderer applies
// them to its image-based light).
#extension GL_GOOGLE_include_directive : require
#include "kernel/pathtrace.glsl"
#include "pixel.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

#include "random.glsl"
#include "camera.glsl"
#include "environment.glsl"
#include "shading.glsl"

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

uint nonfinite_bit(vec3 v, uint bit) {
    return (any(isnan(v)) || any(isinf(v))) ? bit : 0u;
}

void main() {
    uvec2 pixel = tile_pixel();
    uvec2 size = params.size;
    if (any(greaterThanEqual(pixel, size))) {
        return;
    }
    uint index = pixel.y * size.x + pixel.x;
    uint sample_index = params.sample_index;
    uint seed = params.seed;
    uint max_bounces = params.max_bounces;
    uint rr_depth = params.rr_depth;

    vec4 jitter = rand4(pixel, sample_index, rng_stream(0u, RNG_CAMERA), seed);
    vec3 origin = params.camera.origin;
    vec3 dir = camera_ray(params.camera.forward, params.camera.right, params.camera.up,
                          vec2(pixel) + jitter.xy, size);

    vec3 radiance = vec3(0.0);
    vec3 throughput = vec3(1.0);
    uint nonfinite = 0u;  // NONFINITE_* bits of the stages that produced a non-finite value
    float prev_pdf = 0.0;  // solid-angle pdf of the BSDF sample that made this ray; 0 for the camera
    vec4 albedo = vec4(params.env, 0.0);
    vec4 normal_depth = vec4(0.0, 0.0, 0.0, BVH_INF);

    for (uint depth = 0u;; ++depth) {
        Hit hit;
        if (!bvh_closest(origin, dir, 0.0, BVH_INF, hit)) {
            if (HAS_ENV_MAP) {
                float w = 1.0;
                if (params.env_nee != 0u && prev_pdf > 0.0) {
                    w = bsdf_hit_weight(prev_pdf, env_pdf(dir, params.env_size));
                }
                vec3 c = throughput * env_radiance(dir, params.env_size) * params.env * w;
                radiance += c;
                nonfinite |= nonfinite_bit(c, NONFINITE_ENVIRONMENT);
            } else {
                radiance += throughput * params.env;
            }
            break;
        }
        uint tri = hit.tri;
        vec3 ng = tri_normal(tri);
        float area = 0.5 * length(ng);
        ng = normalize(ng);
        vec3 wo = -dir;
        vec3 p = origin + hit.t * dir;

        // Emission, weighted against the light-sampling strategy that could have found it.
        vec4 uv = tri_uv(tri, hit.bary);
        vec3 le = emitted(tri, hit.bary, ng, wo);
        if (any(greaterThan(le, vec3(0.0)))) {
            float w = 1.0;
            if (HAS_LIGHTS && prev_pdf > 0.0) {
                float light_pdf = emissive_pdf(tri, area, hit.t, ng, wo);
                w = bsdf_hit_weight(prev_pdf, light_pdf);
            }
            vec3 c = throughput * le * w;
            radiance += c;
            nonfinite |= nonfinite_bit(c, NONFINITE_EMISSION);
        }

        // Shading frame: interpolated, normal-mapped normal, on the same side as the viewer.
        bool front = dot(ng, wo) >= 0.0;
        if (!front) {
            ng = -ng;
        }
        uint material = tri_material(tri);
        vec3 n = shading_normal(tri, hit.bary, ng, uv);
        vec3 t;
        vec3 b;
        basis(n, t, b);
        vec3 wo_local = vec3(dot(wo, t), dot(wo, b), dot(wo, n));
        Surface s = material_surface(material, uv);
        s.base *= tri_color(tri, hit.bary).rgb;
        if (HAS_TRANSMISSION) {
            // A refracting boundary: glass (ior) behind the front face, air behind the back.
            float ior = material_vec(material, 3u).y;
            s.eta = front ? ior : 1.0 / ior;
        }
        if (depth == 0u) {
            albedo = vec4(s.base, 1.0);
            normal_depth = vec4(n, hit.t);
        }
        // KHR_materials_unlit, modelled as an emitter of its base colour that scatters nothing:
        // the path ends here, and no light sampling finds it (BSDF-sampled rays alone, weight 1).
        if (HAS_UNLIT && (material_uvec(material, 4u).x & MATERIAL_UNLIT) != 0u) {
            radiance += throughput * s.base;
            break;
        }
        if (depth >= max_bounces || wo_local.z <= 0.0) {
            break;
        }

        // Next-event estimation: one emissive triangle by power, a uniform point on it.
        if (HAS_LIGHTS && params.light_count > 0u && LIGHT_SAMPLING) {
            vec4 u = rand4(pixel, sample_index, rng_stream(depth, RNG_EMISSIVE_NEE), seed);
            vec3 wi_local;
            vec3 l_emit;
            float light_pdf;
            if (sample_emissive(p, ng, t, b, n, surface_transmits(s), u.xyz, params.light_count, wi_local, l_emit,
                                light_pdf)) {
                vec3 f = bsdf_eval(s, wo_local, wi_local);
                float w = light_sample_weight(light_pdf, bsdf_pdf(s, wo_local, wi_local));
                vec3 c = throughput * f * abs(wi_local.z) * l_emit * (w / light_pdf);
                radiance += c;
                nonfinite |= nonfinite_bit(c, NONFINITE_EMISSIVE_NEE);
            }
        }

        // Punctual lights: delta distributions, so light sampling is the only strategy (no MIS).
        if (HAS_PUNCTUAL) {
            float u = rand4(pixel, sample_index, rng_stream(depth, RNG_PUNCTUAL), seed).x;
            vec3 c = throughput * punctual_direct(p, ng, t, b, n, s, wo_local, params.punctual_count, u);
            radiance += c;
            nonfinite |= nonfinite_bit(c, NONFINITE_PUNCTUAL);
        }

        // The environment map, importance-sampled by luminance x sin(theta), weighted by MIS.
        if (HAS_ENV_MAP && params.env_nee != 0u && LIGHT_SAMPLING) {
            vec4 u = rand4(pixel, sample_index, rng_stream(depth, RNG_ENV_NEE), seed);
            float pdf;
            vec3 wi = env_sample(u, params.env_size, pdf);
            vec3 wi_local;
            if (pdf > 0.0 && light_reaches(p, ng, t, b, n, surface_transmits(s), wi, false, wi, wi_local)) {
                vec3 f = bsdf_eval(s, wo_local, wi_local);
                float w = light_sample_weight(pdf, bsdf_pdf(s, wo_local, wi_local));
                vec3 le = env_radiance(wi, params.env_size) * params.env;
                vec3 c = throughput * f * abs(wi_local.z) * le * (w / pdf);
                radiance += c;
                nonfinite |= nonfinite_bit(c, NONFINITE_ENV_NEE);
            }
        }

        // Continue the path by sampling the BSDF.
        vec4 u = rand4(pixel, sample_index, rng_stream(depth, RNG_BSDF), seed);
        vec3 wi_local;
        vec3 weight;
        float pdf;
        if (!bsdf_sample(s, wo_local, u.xyz, wi_local, weight, pdf)) {
            break;
        }
        vec3 wi = wi_local.x * t + wi_local.y * b + wi_local.z * n;
        bool transmitted = wi_local.z < 0.0;
        float side = dot(wi, ng);
        if (transmitted ? side >= 0.0 : side <= 0.0) {
            break;  // the shading normal and the geometry disagree about the side
        }
        nonfinite |= nonfinite_bit(weight * float(pdf), NONFINITE_BSDF_SAMPLE);
        throughput *= weight;
        // Light sampling covers both sides of a transmitting surface, so an emitter or the
        // environment reached either way is weighed by MIS against it.
        prev_pdf = pdf;
        if (depth + 1u >= rr_depth) {
            float q = clamp(max3(throughput), 0.05, 1.0);
            if (u.w >= q) {
                break;
            }
            throughput /= q;
        }
        origin = offset_ray(p, transmitted ? -ng : ng);
        dir = wi;
    }

    if (any(isnan(radiance)) || any(isinf(radiance))) {
        atomicAdd(stats.nonfinite_samples, 1u);
        atomicOr(stats.nonfinite_sources, nonfinite);
        radiance = vec3(0.0);
    }
    float n_samples = float(sample_index + 1u);
    vec4 mean = sample_index == 0u ? vec4(0.0) : accum[index];
    vec4 m2 = sample_index == 0u ? vec4(0.0) : moment[index];
    accum[index] = vec4(mean.rgb + (radiance - mean.rgb) / n_samples, n_samples);
    moment[index] = vec4(m2.rgb + (radiance * radiance - m2.rgb) / n_samples, 0.0);
    if (sample_index == 0u) {
        aov_albedo[index] = albedo;
        aov_normal_depth[index] = normal_depth;
    }
}
