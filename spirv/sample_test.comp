#version 460
// Test-only: draws directions with the renderer's own sampling routines (sampling.glsl,
// bsdf.glsl) and evaluates their pdfs at given directions, for the chi-square tests (modes 0
// and 1); mode 2 evaluates bsdf_eval for tests/brdf.rs; mode 3 the dielectric's bsdf_eval and
// bsdf_pdf at given directions, for tests/sampling/'s check that it samples wherever it
// scatters; mode 4 the thin-film Fresnel of KHR_materials_iridescence (tests/iridescence.rs);
// mode 5 bsdf_sample's weights (the white furnace, tests/anisotropy.rs); modes 6 and 7 the path
// tracer's numbers (random.glsl's qmc4, tests/sampling/); mode 8 is mode 0 with sample reuse
// (SAMPLE_REUSE: bsdf_sample's lobe chosen by u.y, stretched back).
#extension GL_GOOGLE_include_directive : require
#include "kernel/sample_test.glsl"

KERNEL_LOCAL_SIZE;

#define SAMPLE_REUSE (params.mode == 8u)

#include "random.glsl"
#include "bsdf.glsl"

// The sheen's albedo table: tests/sampling/ appends its texels to the directions.
vec4 sheen_table_texel(uint t) {
    return directions[uint(directions.length()) - SHEEN_TABLE_TEXELS + t];
}

// Sampler 8: an iridescent surface (KHR_materials_iridescence): base (0.8, 0.6, 0.4), metallic
// 0.3, alpha `alpha`, under a film of ior 1.8 and 350 nm, weight 1 (the lobes' probabilities
// follow its Fresnel).
// Samplers 2-4: the whole BSDF of a white transmissive dielectric (reflection + transmission,
// through bsdf_sample / bsdf_pdf): 2 entering glass (eta 1.5), 3 leaving it (eta 1/1.5),
// 4 thin-walled. Sampler 5: an opaque grey dielectric (alpha 0.5) under a clear coat of weight 1
// and `alpha` (KHR_materials_clearcoat); sampler 7 the same with the coat's normal tilted.
// Sampler 6: the grey dielectric under a sheen of roughness sqrt(`alpha`) (KHR_materials_sheen)
// under a clear coat. Sampler 10: a diffusely transmitting dielectric
// (KHR_materials_diffuse_transmission). Sampler 11: the uniform cone of sized lights' shadow
// rays (sampling.glsl), 1 - cos θmax = `alpha`.
Surface dielectric(float alpha) {
    if (params.kind == 5u || params.kind == 7u) {
        Surface s;
        s.base = vec3(0.8);
        s.metallic = 0.0;
        s.f0 = vec3(0.04);
        s.f90 = 1.0;
        s.alpha = 0.25;
        s.transmission = 0.0;
        s.eta = 1.5;
        s.thin = true;
        s.coat = 1.0;
        s.coat_alpha = alpha;
        // Sampler 7: the coat's own normal tilted 28 degrees from the shading normal (a base normal
        // map, or the coat's normal map).
        s.coat_n = params.kind == 7u ? normalize(vec3(0.5, 0.2, 1.0)) : vec3(0.0, 0.0, 1.0);
        s.sheen = vec3(0.0);
        s.sheen_roughness = 1.0;
        s.iridescence = 0.0;
        s.iridescence_ior = 1.3;
        s.iridescence_thickness = 0.0;
        s.anisotropy = 0.0;
        s.aniso_dir = vec2(1.0, 0.0);
        s.diffuse_transmission = 0.0;
        s.diffuse_transmission_color = vec3(1.0);
        s.thickness = 0.0;
        return s;
    }
    if (params.kind == 8u) {
        Surface s;
        s.base = vec3(0.8, 0.6, 0.4);
        s.metallic = 0.3;
        s.f0 = vec3(0.04);
        s.f90 = 1.0;
        s.alpha = alpha;
        s.transmission = 0.0;
        s.eta = 1.5;
        s.thin = true;
        s.coat = 0.0;
        s.coat_alpha = 1.0;
        s.coat_n = vec3(0.0, 0.0, 1.0);
        s.sheen = vec3(0.0);
        s.sheen_roughness = 1.0;
        s.iridescence = 1.0;
        s.iridescence_ior = 1.8;
        s.iridescence_thickness = 350.0;
        s.anisotropy = 0.0;
        s.aniso_dir = vec2(1.0, 0.0);
        s.diffuse_transmission = 0.0;
        s.diffuse_transmission_color = vec3(1.0);
        s.thickness = 0.0;
        return s;
    }
    if (params.kind == 6u) {
        // KHR_materials_sheen: a coloured sheen of roughness sqrt(alpha) over the grey
        // dielectric, under a clear coat of weight 0.5 and alpha 0.1.
        Surface s;
        s.base = vec3(0.8);
        s.metallic = 0.0;
        s.f0 = vec3(0.04);
        s.f90 = 1.0;
        s.alpha = 0.25;
        s.transmission = 0.0;
        s.eta = 1.5;
        s.thin = true;
        s.coat = 0.5;
        s.coat_alpha = 0.1;
        s.coat_n = vec3(0.0, 0.0, 1.0);
        s.sheen = vec3(0.9, 0.6, 0.3);
        s.sheen_roughness = max(sqrt(alpha), SHEEN_ROUGHNESS_MIN);
        s.iridescence = 0.0;
        s.iridescence_ior = 1.3;
        s.iridescence_thickness = 0.0;
        s.anisotropy = 0.0;
        s.aniso_dir = vec2(1.0, 0.0);
        s.diffuse_transmission = 0.0;
        s.diffuse_transmission_color = vec3(1.0);
        s.thickness = 0.0;
        return s;
    }
    if (params.kind == 10u) {
        // KHR_materials_diffuse_transmission: a grey dielectric (base params.anisotropy.w, alpha
        // `alpha`, KHR_materials_specular's factor params.anisotropy.z: 0 takes the Fresnel
        // away) whose diffuse lobe transmits a share params.anisotropy.x through the back,
        // tinted (1, b, b^2) for b = anisotropy_base, the surface transmitting
        // (KHR_materials_transmission) a share params.anisotropy.y, thin-walled.
        Surface s;
        s.base = vec3(params.anisotropy.w);
        s.metallic = 0.0;
        s.f0 = vec3(0.04 * params.anisotropy.z);
        s.f90 = params.anisotropy.z;
        s.alpha = alpha;
        s.transmission = params.anisotropy.y;
        s.eta = 1.5;
        s.thin = true;
        s.coat = 0.0;
        s.coat_alpha = 1.0;
        s.coat_n = vec3(0.0, 0.0, 1.0);
        s.sheen = vec3(0.0);
        s.sheen_roughness = 1.0;
        s.iridescence = 0.0;
        s.iridescence_ior = 1.3;
        s.iridescence_thickness = 0.0;
        s.anisotropy = 0.0;
        s.aniso_dir = vec2(1.0, 0.0);
        s.diffuse_transmission = params.anisotropy.x;
        s.diffuse_transmission_color = vec3(1.0, params.anisotropy_base, params.anisotropy_base * params.anisotropy_base);
        s.thickness = 0.0;
        return s;
    }
    if (params.kind == 9u) {
        // KHR_materials_anisotropy: a surface of base colour `anisotropy_base`, metallic
        // params.anisotropy.w (0: the dielectric's reflection over its diffuse lobe), alpha
        // `alpha`, strength params.anisotropy.x along the unit direction params.anisotropy.yz.
        Surface s;
        s.base = vec3(params.anisotropy_base);
        s.metallic = params.anisotropy.w;
        s.f0 = vec3(0.04);
        s.f90 = 1.0;
        s.alpha = alpha;
        s.transmission = 0.0;
        s.eta = 1.5;
        s.thin = true;
        s.coat = 0.0;
        s.coat_alpha = 1.0;
        s.coat_n = vec3(0.0, 0.0, 1.0);
        s.sheen = vec3(0.0);
        s.sheen_roughness = 1.0;
        s.iridescence = 0.0;
        s.iridescence_ior = 1.3;
        s.iridescence_thickness = 0.0;
        s.anisotropy = params.anisotropy.x;
        s.aniso_dir = params.anisotropy.yz;
        s.diffuse_transmission = 0.0;
        s.diffuse_transmission_color = vec3(1.0);
        s.thickness = 0.0;
        return s;
    }
    Surface s;
    s.base = vec3(1.0);
    s.metallic = 0.0;
    s.f0 = vec3(0.04);
    s.f90 = 1.0;
    s.alpha = alpha;
    s.transmission = 1.0;
    s.eta = params.kind == 3u ? 1.0 / 1.5 : 1.5;
    s.thin = params.kind == 4u;
    s.coat = 0.0;
    s.coat_alpha = 1.0;
    s.coat_n = vec3(0.0, 0.0, 1.0);
    s.sheen = vec3(0.0);
    s.sheen_roughness = 1.0;
    s.iridescence = 0.0;
    s.iridescence_ior = 1.3;
    s.iridescence_thickness = 0.0;
    s.anisotropy = 0.0;
    s.aniso_dir = vec2(1.0, 0.0);
    s.diffuse_transmission = 0.0;
    s.diffuse_transmission_color = vec3(1.0);
    s.thickness = 0.0;
    return s;
}

float sampler_pdf(vec3 wo, vec3 wi, float alpha) {
    if (params.kind == 0u) {
        return pdf_cosine_hemisphere(wi);
    }
    if (params.kind == 11u) {
        // Sampler 11: the uniform cone about +z with 1 - cos θmax = `alpha` (a sample on its edge
        // may round 1e-7 past it).
        return 1.0 - wi.z <= alpha + 1e-6 ? pdf_uniform_cone(alpha) : 0.0;
    }
    if (params.kind >= 2u) {
        return bsdf_pdf(dielectric(alpha), wo, wi);
    }
    vec3 h = wo + wi;
    float len = length(h);
    return len > 0.0 ? micro_pdf(wo, h / len, alpha) : 0.0;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) {
        return;
    }
    vec3 wo = params.wo;
    float alpha = params.alpha;
    if (params.mode == 2u) {
        // bsdf_eval of an opaque glTF metallic-roughness surface (ior 1.5, specular 1), each
        // case three vec4s: (wo, alpha), (wi, metallic), (base colour, unused).
        vec4 o = directions[3u * i];
        vec4 d = directions[3u * i + 1u];
        Surface s;
        s.base = directions[3u * i + 2u].rgb;
        s.metallic = d.w;
        s.f0 = vec3(0.04);
        s.f90 = 1.0;
        s.alpha = o.w;
        s.transmission = 0.0;
        s.eta = 1.5;
        s.thin = true;
        s.coat = 0.0;
        s.coat_alpha = 1.0;
    s.coat_n = vec3(0.0, 0.0, 1.0);
        s.sheen = vec3(0.0);
        s.sheen_roughness = 1.0;
        s.iridescence = 0.0;
        s.iridescence_ior = 1.3;
        s.iridescence_thickness = 0.0;
        s.anisotropy = 0.0;
        s.aniso_dir = vec2(1.0, 0.0);
        s.diffuse_transmission = 0.0;
        s.diffuse_transmission_color = vec3(1.0);
        s.thickness = 0.0;
        results[i] = vec4(bsdf_eval(s, o.xyz, d.xyz), 0.0);
        return;
    }
    if (params.mode == 4u) {
        // KHR_materials_iridescence's film Fresnel, each case two vec4s: (cos, thickness nm,
        // film ior, unused), (base F0 rgb, unused).
        vec4 c = directions[2u * i];
        vec3 f0 = directions[2u * i + 1u].rgb;
        results[i] = vec4(iridescent_fresnel(c.z, c.y, f0, c.x), 0.0);
        return;
    }
    if (params.mode == 6u || params.mode == 7u) {
        // The path tracer's numbers (random.glsl's qmc4): mode 6 sample i of pixel (kind, 0),
        // mode 7 sample 5 of pixel (i, kind); stream 2.
        results[i] = params.mode == 6u ? qmc4(uvec2(params.kind, 0u), i, 2u, params.seed)
                                       : qmc4(uvec2(i, params.kind), 5u, 2u, params.seed);
        return;
    }
    if (params.mode == 5u) {
        // bsdf_sample's weights f |cos| / pdf (0 for a failed sample), whose mean is the
        // directional albedo: the white furnace.
        vec4 u = rand4(uvec2(i, 0u), 0u, 0u, params.seed);
        vec3 wi;
        vec3 weight;
        float pdf;
        bool ok = bsdf_sample(dielectric(alpha), wo, u.xyz, wi, weight, pdf);
        results[i] = ok ? vec4(weight, 1.0) : vec4(0.0);
        return;
    }
    if (params.mode == 3u) {
        vec3 wi = directions[i].xyz;
        Surface s = dielectric(alpha);
        results[i] = vec4(bsdf_eval(s, wo, wi), bsdf_pdf(s, wo, wi));
        return;
    }
    if (params.mode == 0u || params.mode == 8u) {
        vec4 u = rand4(uvec2(i, 0u), 0u, 0u, params.seed);
        vec3 wi;
        if (params.kind == 11u) {
            wi = sample_uniform_cone(u.xy, alpha);
        } else if (params.kind >= 2u) {
            vec3 weight;
            float pdf;
            // A failed sample (outside its lobe's side, or beyond the critical angle) reports pdf 0.
            if (!bsdf_sample(dielectric(alpha), wo, u.xyz, wi, weight, pdf)) {
                results[i] = vec4(0.0);
                return;
            }
        } else if (params.kind == 0u) {
            wi = sample_cosine_hemisphere(u.xy);
        } else {
            wi = reflect(-wo, micro_sample(wo, alpha, u.xy));
        }
        results[i] = vec4(wi, sampler_pdf(wo, wi, alpha));
    } else {
        vec3 wi = directions[i].xyz;
        results[i] = vec4(wi, sampler_pdf(wo, wi, alpha));
    }
}
