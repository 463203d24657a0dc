// The glTF 2.0 metallic-roughness BSDF (Appendix B) with KHR_materials_specular, as eval /
// sample / pdf in the local shading frame (z = shading normal; wo and wi point away).
//
//   material   = mix(dielectric, metal, metallic)
//   metal      = F_schlick(baseColor, 1, V.H) * D G1(V) G1(L) / (4 |N.V| |N.L|)
//   dielectric = (1 - max(F)) * baseColor / pi + F * D G1(V) G1(L) / (4 |N.V| |N.L|)
//   F          = F_schlick(min(f0(ior) * specularColor, 1) * specular, specular, V.H)
//
// The microfacet distribution is GGX (the specification) or, for comparison, Beckmann: the
// including kernel declares `const bool BECKMANN` (a specialization constant).
#ifndef UMBRA_BSDF_GLSL
#define UMBRA_BSDF_GLSL

#include "sampling.glsl"

// Smallest alpha: below it (roughness < 0.01) the lobe is treated as this sharp, so D stays finite.
const float ALPHA_MIN = 1e-4;

struct Surface {
    vec3 base;
    float metallic;
    vec3 f0;      // dielectric F0 (ior, specular colour and factor applied)
    float f90;    // dielectric F90 (the specular factor)
    float alpha;
};

float max3(vec3 v) {
    return max(v.x, max(v.y, v.z));
}

float luminance(vec3 c) {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

vec3 fresnel_schlick(vec3 f0, vec3 f90, float cos_theta) {
    float m = clamp(1.0 - cos_theta, 0.0, 1.0);
    float m2 = m * m;
    return f0 + (f90 - f0) * (m2 * m2 * m);
}

float micro_d(vec3 h, float a) {
    return BECKMANN ? beckmann_d(h, a) : ggx_d(h, a);
}

// The specular term's G1(wo) G1(wi) / (4 |wo.z| |wi.z|), evaluated without the 0/0 that the
// quotient gives at grazing angles once the cosines' product flushes to zero.
float micro_visibility(vec3 wo, vec3 wi, float a) {
    float v = BECKMANN ? beckmann_g1_over_cos(wo, a) * beckmann_g1_over_cos(wi, a)
                       : ggx_g1_over_cos(wo, a) * ggx_g1_over_cos(wi, a);
    return 0.25 * v;
}

// A half vector for wo: GGX visible normals, or Beckmann D(h) cos(theta_h).
vec3 micro_sample(vec3 wo, float a, vec2 u) {
    return BECKMANN ? sample_beckmann(a, u) : sample_ggx_vndf(wo, a, u);
}

// Solid-angle density of wi = reflect(-wo, h) under micro_sample.
float micro_pdf(vec3 wo, vec3 h, float a) {
    float oh = dot(wo, h);
    if (oh <= 0.0) {
        return 0.0;
    }
    float pdf_h = BECKMANN ? pdf_beckmann(h, a) : pdf_ggx_vndf(wo, h, a);
    return pdf_h / (4.0 * oh);
}

vec3 bsdf_eval(Surface s, vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) {
        return vec3(0.0);
    }
    vec3 h = normalize(wo + wi);
    float oh = max(dot(wo, h), 0.0);
    float spec = micro_d(h, s.alpha) * micro_visibility(wo, wi, s.alpha);
    vec3 f_dielectric = fresnel_schlick(s.f0, vec3(s.f90), oh);
    vec3 dielectric = (1.0 - max3(f_dielectric)) * s.base * INV_PI + f_dielectric * spec;
    vec3 metal = fresnel_schlick(s.base, vec3(1.0), oh) * spec;
    return mix(dielectric, metal, s.metallic);
}

// Probability of sampling the specular lobe: its share of the Fresnel-weighted albedo at wo.
float specular_probability(Surface s, vec3 wo) {
    float f = max3(fresnel_schlick(s.f0, vec3(s.f90), wo.z));
    float specular = mix(f, 1.0, s.metallic);
    float diffuse = (1.0 - s.metallic) * (1.0 - f) * luminance(s.base);
    float total = specular + diffuse;
    return total > 0.0 ? specular / total : 0.5;
}

float bsdf_pdf(Surface s, vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) {
        return 0.0;
    }
    float p = specular_probability(s, wo);
    vec3 h = normalize(wo + wi);
    return p * micro_pdf(wo, h, s.alpha) + (1.0 - p) * pdf_cosine_hemisphere(wi);
}

// Samples wi; weight = f cos / pdf. False when the sample is below the surface or has no density.
bool bsdf_sample(Surface s, vec3 wo, vec3 u, out vec3 wi, out vec3 weight, out float pdf) {
    weight = vec3(0.0);
    pdf = 0.0;
    if (u.x < specular_probability(s, wo)) {
        vec3 h = micro_sample(wo, s.alpha, u.yz);
        wi = reflect(-wo, h);
    } else {
        wi = sample_cosine_hemisphere(u.yz);
    }
    if (wi.z <= 0.0) {
        return false;
    }
    pdf = bsdf_pdf(s, wo, wi);
    if (!(pdf > 0.0)) {
        return false;
    }
    weight = bsdf_eval(s, wo, wi) * wi.z / pdf;
    return true;
}

#endif
