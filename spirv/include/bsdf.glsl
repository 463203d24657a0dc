// The glTF 2.0 metallic-roughness BSDF (Appendix B) with KHR_materials_specular, as eval /
// sample / pdf in the local shading frame (z = shading normal; wo and wi point away).
//
//   material   = mix(dielectric, metal, metallic)
//   metal      = F_schlick(baseColor, 1, V.H) * D G1(V) G1(L) / (4 |N.V| |N.L|)
//   dielectric = (1 - max(F)) * mix(baseColor / pi, baseColor * btdf, transmission)
//                + F * D G1(V) G1(L) / (4 |N.V| |N.L|)
//   F          = F_schlick(min(f0(ior) * specularColor, 1) * specular, specular, V.H)
//
// KHR_materials_transmission's btdf is a rough dielectric on the other side of the surface:
// thin-walled (the glTF default: the reflection lobe mirrored through the surface, no bending),
// or, for a KHR_materials_volume boundary, Walter et al. 2007's refraction BTDF (Snell's law
// through the microfacet, eq. 21, with the glTF Fresnel; leaving the denser side, Schlick takes
// the transmitted angle and total internal reflection gives F = 1).
//
// KHR_materials_clearcoat layers a clear GGX coat (ior 1.5, its own alpha, no Fresnel inside
// the lobe) over all of it, weighted as the extension's fresnel_coat says:
//
//   coated = mix(material, D G1(V) G1(L) / (4 |N.V| |N.L|), clearcoat * F_schlick(0.04, 1, N.V))
//
// with N.V (not V.H) in the weight, so for each wo the coated BSDF is a convex mix of two lobes of
// albedo at most 1 (energy conserving). N is the coat's own normal (`coat_n`, in the shading
// frame): the extension gives the coat the unmapped normal, tilted only by its own normal map,
// while the material under it takes the shading frame's (normal-mapped) z; the coat's lobe is
// evaluated and sampled in a frame around coat_n, and light must arrive and leave above both. A
// surface without a coat (`coat` 0: a kernel not specialised for it sets the constant 0) costs
// nothing: the branches fold; with coat_n the constant (0, 0, 1) the coat's frame folds too.
//
// KHR_materials_sheen lies between the two (the coat over the sheen over the material): the
// sheen lobe is the extension's "Charlie" one (Conty Estevez and Kulla 2017: D = (2 + 1/a)
// sin(theta_h)^(1/a) / 2pi with a = sheenRoughness^2, and their fitted Lambda in the visibility
// 1 / ((1 + Lambda(N.V) + Lambda(N.L)) 4 |N.V| |N.L|), no Fresnel), and the material under it is
// scaled as the extension's albedo scaling says:
//
//   sheened = sheenColor D V + material * max(0, min(1 - max3(sheenColor) E(N.V),
//                                                    1 - max3(sheenColor) E(N.L)))
//
// with E the lobe's directional albedo, tabulated by src/sheen.rs at build time (its size in the
// generated sheen_albedo.glsl, its texels after the scene's materials: sheen_table_texel).
// Transmitted light (N.L < 0) takes E(|N.L|). The fitted Lambda lets E exceed 1 at n.v < 0.01 for
// sheen roughness below 0.26 (src/sheen.rs): the scaling is clamped at 0 there. The path tracer
// samples the sheen as its own lobe, from the cosine-weighted hemisphere. A surface without a
// sheen (`sheen` 0: a kernel not specialised for it sets the constant) costs nothing.
//
// KHR_materials_iridescence puts a thin dielectric film (its ior and thickness in nm) on the
// material: the dielectric's and the metal's Fresnel F become
//
//   F = mix(F, F_film(cos), iridescence)
//
// with F_film the film's interference reflectance (iridescent_fresnel), evaluated at the same
// cosine as F (V.H in the lobes; leaving the denser side of a refracting boundary, the transmitted
// angle's, as dielectric_fresnel takes it) over the dielectric's F0 (ior and specular applied) or
// the metal's base colour. The dielectric's diffuse and transmitted light keep 1 - max3(F), as the
// extension's rgb_mix says. The clear coat and the sheen lie over it unchanged (the extension
// ignores the coat-film interface). A surface without a film (`iridescence` 0: a kernel not
// specialised for it sets the constant) costs nothing.
//
// KHR_materials_diffuse_transmission splits the dielectric's diffuse lobe (what transmission
// leaves of it) into reflection and a Lambertian lobe on the other side of the surface, tinted by
// its own colour (not the base colour), as the extension's layering says:
//
//   diffuse = mix(baseColor / pi, diffuseTransmissionColor / pi [wi below], diffuseTransmission)
//
// under the same 1 - max3(F) as the diffuse reflection, F taken at the half vector of wo and wi
// mirrored to wo's side (as thin-walled transmission takes it). It is thin-walled: the light
// leaves the back unbent; in a KHR_materials_volume it enters the medium (the path tracer
// attenuates the segment inside). The path tracer samples it as its own lobe (the cosine
// hemisphere below). A surface without it (`diffuse_transmission` 0: a kernel not specialised
// for it sets the constant) costs nothing.
//
// KHR_materials_anisotropy makes the material's specular lobes (metal, dielectric reflection and
// transmission; not the coat) anisotropic GGX: alpha_t = mix(alpha, 1, strength^2) along the
// anisotropy direction (`aniso_dir`, a unit vector in the shading frame's xy plane), alpha_b =
// alpha across it; D and Smith's G1 are Heitz 2014's anisotropic ones and half vectors are sampled
// from the visible normals (Heitz 2018's stretch), all in a frame whose x is the direction (the
// spec_* functions). A surface without anisotropy (`anisotropy` 0: a kernel not specialised for
// it sets the constant) takes the isotropic micro_* functions: the branches fold. Anisotropic
// lobes are GGX with visible-normal sampling whatever BECKMANN and GGX_WALTER say (those compare
// isotropic distributions and samplers).
//
// The microfacet distribution is GGX (the specification) or, for comparison, Beckmann: the
// including kernel declares `const bool BECKMANN` (a specialization constant). Half vectors are
// sampled from GGX's visible normals (Heitz 2018) or, with `const bool GGX_WALTER` (also the
// kernel's), from D(h) cos(theta_h) as Walter et al. 2007 do, for reflection and transmission
// alike; Beckmann always samples D(h) cos(theta_h). The BSDF itself is the same either way.
//
// bsdf_sample picks a lobe with one number and samples the lobe's direction with two others
// (u.x; u.yz), unless the including kernel defines SAMPLE_REUSE true (the path tracer, for its
// low-discrepancy numbers): then u.y picks the lobe and the lobe's share of it, stretched back
// over [0, 1) (random.glsl's stretch), is the direction's first number, so each lobe's
// directions keep the stratification of the (u.y, u.z) pair (Mitsuba's sample reuse). The same
// density either way.
#ifndef UMBRA_BSDF_GLSL
#define UMBRA_BSDF_GLSL

#ifndef SAMPLE_REUSE
#define SAMPLE_REUSE false
#endif

#include "random.glsl"
#include "sampling.glsl"
#include "sheen_albedo.glsl"

// Texel t (entries 4t..4t+3) of the sheen's albedo table: the including kernel defines it
// (shading.glsl from the scene's material texels, where src/gpu/scene.rs appends the table for
// a scene with a sheen).
vec4 sheen_table_texel(uint t);

// Smallest alpha: below it (roughness < 0.01) the lobe is treated as this sharp, so D stays finite.
const float ALPHA_MIN = 1e-4;

struct Surface {
    vec3 base;
    float metallic;
    vec3 f0;      // dielectric F0 (ior, specular colour and factor applied)
    float f90;    // dielectric F90 (the specular factor)
    float alpha;
    float transmission;  // share of the dielectric's diffuse lobe that transmits instead
    float eta;           // refracting boundary: index below the surface (-z) / index above (+z, wo's side)
    bool thin;           // thin-walled transmission (no refraction); also every opaque surface
    float coat;          // KHR_materials_clearcoat's weight (0: no coat)
    float coat_alpha;    // the coat's GGX alpha
    vec3 coat_n;         // the coat's unit normal in the shading frame ((0, 0, 1): the shading normal)
    vec3 sheen;              // KHR_materials_sheen's colour (0: no sheen)
    float sheen_roughness;   // its roughness, at least SHEEN_ROUGHNESS_MIN
    float iridescence;            // KHR_materials_iridescence's weight (0: no film)
    float iridescence_ior;        // the film's index of refraction
    float iridescence_thickness;  // the film's thickness, nm
    float anisotropy;        // KHR_materials_anisotropy's strength in [0, 1] (0: isotropic)
    vec2 aniso_dir;          // the anisotropy direction: unit, in the shading frame's xy plane
    float diffuse_transmission;        // KHR_materials_diffuse_transmission's share (0: none)
    vec3 diffuse_transmission_color;   // its colour
    float thickness;     // KHR_materials_volume's thickness (the hybrid's attenuation; 0: none)
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

// A half vector for wo: GGX visible normals, GGX D(h) cos(theta_h) (GGX_WALTER), or Beckmann
// D(h) cos(theta_h).
vec3 micro_sample(vec3 wo, float a, vec2 u) {
    if (BECKMANN) {
        return sample_beckmann(a, u);
    }
    return GGX_WALTER ? sample_ggx_walter(a, u) : sample_ggx_vndf(wo, a, u);
}

// Density of the half vector h under micro_sample(wo).
float micro_pdf_h(vec3 wo, vec3 h, float a) {
    if (BECKMANN) {
        return pdf_beckmann(h, a);
    }
    return GGX_WALTER ? pdf_ggx_walter(h, a) : pdf_ggx_vndf(wo, h, a);
}

// Solid-angle density of wi = reflect(-wo, h) under micro_sample.
float micro_pdf(vec3 wo, vec3 h, float a) {
    float oh = dot(wo, h);
    if (oh <= 0.0) {
        return 0.0;
    }
    return micro_pdf_h(wo, h, a) / (4.0 * oh);
}

// CIE 1931 XYZ to linear Rec. 709 (sRGB primaries, D65), column by column.
const mat3 XYZ_TO_REC709 = mat3(3.2404542, -0.9692660, 0.0556434, -1.5371385, 1.8760108, -0.2040259,
                                -0.4985314, 0.0415560, 1.0572252);

// The colour (linear Rec. 709) of the interference term cos(2 pi opd / lambda + shift) seen
// through the CIE colour matching functions under an equal-energy spectrum, normalised by the
// integral of y: Belcour and Barla's (2017) Gaussian fit of the functions' Fourier transforms, as
// the extension writes it. `opd`: the optical path difference in nm; `shift`: the phase per
// channel of XYZ.
vec3 iridescence_sensitivity(float opd, vec3 shift) {
    float phase = 2.0 * PI * opd * 1.0e-9;
    const vec3 val = vec3(5.4856e-13, 4.4201e-13, 5.2481e-13);
    const vec3 pos = vec3(1.6810e+06, 1.7953e+06, 2.2084e+06);
    const vec3 var = vec3(4.3278e+09, 9.3046e+09, 6.6121e+09);
    vec3 xyz = val * sqrt(2.0 * PI * var) * cos(pos * phase + shift) * exp(-phase * phase * var);
    xyz.x += 9.7470e-14 * sqrt(2.0 * PI * 4.5282e+09) * cos(2.2399e+06 * phase + shift.x)
        * exp(-4.5282e+09 * phase * phase);
    return XYZ_TO_REC709 * (xyz / 1.0685e-7);
}

// KHR_materials_iridescence's thin-film Fresnel (the extension's appendix, after Belcour and
// Barla 2017): a film of index `film_ior` and `thickness` nm between air (index 1) and a base of
// reflectance `base_f0` at normal incidence (its index from F0, per channel), lit at cosine
// `cos1` in the air. Both interfaces by Schlick's form, phase shifts 0 or pi (polarisation
// ignored), the Airy sum's mean and first two interference terms through
// iridescence_sensitivity. Clamped to [0, 1]: the fit's colour can leave the gamut, below 0 (the
// extension's max(I, 0)) and above 1 (by up to 0.28 for a film of index 2.5 over F0 0.85 at
// grazing angles), which would create energy.
vec3 iridescent_fresnel(float film_ior, float thickness, vec3 base_f0, float cos1) {
    float cos2_sq = 1.0 - (1.0 - cos1 * cos1) / (film_ior * film_ior);
    if (cos2_sq < 0.0) {
        return vec3(1.0);  // total internal reflection in a film below the outside's index
    }
    float cos2 = sqrt(cos2_sq);
    // Air to film.
    float r0 = (film_ior - 1.0) / (film_ior + 1.0);
    float r12 = fresnel_schlick(vec3(r0 * r0), vec3(1.0), cos1).x;
    float t121 = 1.0 - r12;
    float phi21 = film_ior < 1.0 ? 0.0 : PI;
    // Film to base.
    vec3 root = sqrt(clamp(base_f0, 0.0, 0.9999));
    vec3 base_ior = (1.0 + root) / (1.0 - root);
    vec3 r1 = (base_ior - film_ior) / (base_ior + film_ior);
    vec3 r23 = fresnel_schlick(r1 * r1, vec3(1.0), cos2);
    vec3 phi23 = mix(vec3(0.0), vec3(PI), lessThan(base_ior, vec3(film_ior)));
    float opd = 2.0 * film_ior * thickness * cos2;
    vec3 phi = phi21 + phi23;
    // The Airy sum: its mean, then the terms of the first two round trips.
    vec3 r123 = clamp(r12 * r23, 1e-5, 0.9999);
    vec3 amplitude = sqrt(r123);
    vec3 rs = t121 * t121 * r23 / (1.0 - r123);
    vec3 f = r12 + rs;
    vec3 cm = (rs - t121) * amplitude;
    f += 2.0 * cm * iridescence_sensitivity(opd, phi);
    cm *= amplitude;
    f += 2.0 * cm * iridescence_sensitivity(2.0 * opd, 2.0 * phi);
    return clamp(f, 0.0, 1.0);
}

// The material's specular lobes (KHR_materials_anisotropy): alpha along the anisotropy
// direction (x) and across it (y).
vec2 aniso_alpha(Surface s) {
    return vec2(mix(s.alpha, 1.0, s.anisotropy * s.anisotropy), s.alpha);
}

// Direction v (shading frame) in the anisotropy frame: x along aniso_dir, z the normal.
vec3 to_aniso(Surface s, vec3 v) {
    vec2 d = s.aniso_dir;
    return vec3(d.x * v.x + d.y * v.y, d.x * v.y - d.y * v.x, v.z);
}

// Direction v of the anisotropy frame back in the shading frame.
vec3 from_aniso(Surface s, vec3 v) {
    vec2 d = s.aniso_dir;
    return vec3(d.x * v.x - d.y * v.y, d.y * v.x + d.x * v.y, v.z);
}

// The material's microfacet distribution at h: micro_d, or anisotropic GGX.
float spec_d(Surface s, vec3 h) {
    if (s.anisotropy > 0.0) {
        return ggx_d_aniso(to_aniso(s, h), aniso_alpha(s));
    }
    return micro_d(h, s.alpha);
}

// The material's G1(wo) G1(wi) / (4 |wo.z| |wi.z|): micro_visibility, or anisotropic GGX's.
float spec_visibility(Surface s, vec3 wo, vec3 wi) {
    if (s.anisotropy > 0.0) {
        vec2 a = aniso_alpha(s);
        return 0.25 * ggx_g1_over_cos_aniso(to_aniso(s, wo), a) * ggx_g1_over_cos_aniso(to_aniso(s, wi), a);
    }
    return micro_visibility(wo, wi, s.alpha);
}

// A half vector of the material's lobes for wo: micro_sample, or anisotropic GGX's visible
// normals.
vec3 spec_sample(Surface s, vec3 wo, vec2 u) {
    if (s.anisotropy > 0.0) {
        return from_aniso(s, sample_ggx_vndf_aniso(to_aniso(s, wo), aniso_alpha(s), u));
    }
    return micro_sample(wo, s.alpha, u);
}

// Density of the half vector h under spec_sample(wo).
float spec_pdf_h(Surface s, vec3 wo, vec3 h) {
    if (s.anisotropy > 0.0) {
        return pdf_ggx_vndf_aniso(to_aniso(s, wo), to_aniso(s, h), aniso_alpha(s));
    }
    return micro_pdf_h(wo, h, s.alpha);
}

// Solid-angle density of wi = reflect(-wo, h) under spec_sample.
float spec_pdf(Surface s, vec3 wo, vec3 h) {
    if (s.anisotropy > 0.0) {
        float oh = dot(wo, h);
        if (oh <= 0.0) {
            return 0.0;
        }
        return spec_pdf_h(s, wo, h) / (4.0 * oh);
    }
    return micro_pdf(wo, h, s.alpha);
}

// The dielectric layer's Fresnel at a microfacet with cos(wo, h) = c, the film's mixed in. Leaving
// the denser side of a refracting boundary (eta < 1), Schlick's form takes the transmitted angle's
// cosine, and beyond the critical angle reflection is total.
vec3 dielectric_fresnel(Surface s, float c) {
    if (!s.thin && s.eta < 1.0) {
        float sin2_t = (1.0 - c * c) / (s.eta * s.eta);
        if (sin2_t >= 1.0) {
            return vec3(1.0);
        }
        c = sqrt(1.0 - sin2_t);
    }
    vec3 f = fresnel_schlick(s.f0, vec3(s.f90), c);
    if (s.iridescence > 0.0) {
        f = mix(f, iridescent_fresnel(s.iridescence_ior, s.iridescence_thickness, s.f0, c), s.iridescence);
    }
    return f;
}

// The metal's Fresnel at a microfacet with cos(wo, h) = c (its F0 the base colour), the film's
// mixed in.
vec3 metal_fresnel(Surface s, float c) {
    vec3 f = fresnel_schlick(s.base, vec3(1.0), c);
    if (s.iridescence > 0.0) {
        f = mix(f, iridescent_fresnel(s.iridescence_ior, s.iridescence_thickness, s.base, c), s.iridescence);
    }
    return f;
}

// The generalized half vector of a refraction from wo (above) to wi (below), facing +z
// (Walter et al. 2007, eq. 16).
vec3 refraction_half_vector(Surface s, vec3 wo, vec3 wi) {
    vec3 h = -(wo + s.eta * wi);
    float len = length(h);
    h = len > 0.0 ? h / len : vec3(0.0, 0.0, 1.0);
    return h.z < 0.0 ? -h : h;
}

// The transmission lobe for wi below the surface (wi.z < 0).
vec3 bsdf_eval_transmission(Surface s, vec3 wo, vec3 wi) {
    float weight = (1.0 - s.metallic) * s.transmission;
    if (!(weight > 0.0)) {
        return vec3(0.0);
    }
    if (s.thin) {
        vec3 wm = vec3(wi.xy, -wi.z);  // mirrored to wo's side
        vec3 h = normalize(wo + wm);
        vec3 f = dielectric_fresnel(s, max(dot(wo, h), 0.0));
        return weight * (1.0 - max3(f)) * s.base * spec_d(s, h) * spec_visibility(s, wo, wm);
    }
    vec3 h = refraction_half_vector(s, wo, wi);
    float oh = dot(wo, h);
    float ih = dot(wi, h);
    if (oh <= 0.0 || ih >= 0.0) {
        return vec3(0.0);
    }
    vec3 f = dielectric_fresnel(s, oh);
    float denom = s.eta * ih + oh;
    // |i.h| |o.h| (1 - F) D G1(o) G1(i) / (|i.n| |o.n| (eta i.h + o.h)^2); micro_visibility
    // carries G1 G1 / (4 |i.n| |o.n|).
    float btdf = -ih * oh * spec_d(s, h) * 4.0 * spec_visibility(s, wo, wi) / (denom * denom);
    return weight * (1.0 - max3(f)) * s.base * btdf;
}

// KHR_materials_diffuse_transmission's Lambertian lobe for wi below the surface (wi.z < 0).
vec3 bsdf_eval_diffuse_transmission(Surface s, vec3 wo, vec3 wi) {
    vec3 wm = vec3(wi.xy, -wi.z);  // mirrored to wo's side
    float oh = max(dot(wo, normalize(wo + wm)), 0.0);
    float weight = (1.0 - s.metallic) * (1.0 - s.transmission) * s.diffuse_transmission;
    return weight * (1.0 - max3(dielectric_fresnel(s, oh))) * s.diffuse_transmission_color * INV_PI;
}

// The material under the coat.
vec3 bsdf_eval_base(Surface s, vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z == 0.0) {
        return vec3(0.0);
    }
    if (wi.z < 0.0) {
        vec3 through = bsdf_eval_transmission(s, wo, wi);
        if (s.diffuse_transmission > 0.0) {
            through += bsdf_eval_diffuse_transmission(s, wo, wi);
        }
        return through;
    }
    vec3 h = normalize(wo + wi);
    float oh = max(dot(wo, h), 0.0);
    float spec = spec_d(s, h) * spec_visibility(s, wo, wi);
    vec3 f_dielectric = dielectric_fresnel(s, oh);
    vec3 dielectric = (1.0 - max3(f_dielectric)) * (1.0 - s.transmission) * s.base * INV_PI + f_dielectric * spec;
    if (s.diffuse_transmission > 0.0) {
        // The share that leaves through the back instead.
        dielectric -= s.diffuse_transmission * (1.0 - max3(f_dielectric)) * (1.0 - s.transmission) * s.base * INV_PI;
    }
    vec3 metal = metal_fresnel(s, oh) * spec;
    return mix(dielectric, metal, s.metallic);
}

// Probabilities of the specular reflection (x), transmission (y), diffuse (z) and diffuse
// transmission (w) lobes: their shares of the Fresnel-weighted albedo at wo. Leaving the denser side of a refracting boundary,
// F at the normal is 1 beyond the critical angle, yet microfacets tilted towards wo still refract
// (a rough boundary's transmission fades over degrees past it: at α 0.1, 37 % of the albedo at
// 45°, 5 % at 60°), so F is taken 9:1 with Schlick's at the unbent angle there: transmission
// keeps a probability wherever it can happen (tests/sampling/), reflection most of it under
// total internal reflection.
// The lobes' estimated albedos at wo: specular reflection (x), transmission (y), diffuse (z),
// diffuse transmission (w, by its colour's luminance).
vec4 lobe_albedos(Surface s, vec3 wo) {
    float f = max3(dielectric_fresnel(s, wo.z));
    if (!s.thin && s.eta < 1.0) {
        f = mix(max3(fresnel_schlick(s.f0, vec3(s.f90), wo.z)), f, 0.9);
    }
    float specular = mix(f, 1.0, s.metallic);
    float rest = (1.0 - s.metallic) * (1.0 - f) * luminance(s.base);
    vec4 a = vec4(specular, rest * s.transmission, rest * (1.0 - s.transmission), 0.0);
    if (s.diffuse_transmission > 0.0) {
        float diffuse = (1.0 - s.metallic) * (1.0 - f) * (1.0 - s.transmission);
        a.z *= 1.0 - s.diffuse_transmission;
        a.w = diffuse * s.diffuse_transmission * luminance(s.diffuse_transmission_color);
    }
    return a;
}

// The sum of the lobes' estimated albedos.
float lobe_albedo_sum(vec4 a) {
    return a.x + a.y + a.z + a.w;
}

vec4 lobe_probabilities(Surface s, vec3 wo) {
    vec4 a = lobe_albedos(s, wo);
    float total = lobe_albedo_sum(a);
    float p_spec = total > 0.0 ? a.x / total : 0.5;
    float p_trans = total > 0.0 ? a.y / total : 0.0;
    float p_through = total > 0.0 ? a.w / total : 0.0;
    return vec4(p_spec, p_trans, 1.0 - p_spec - p_trans - p_through, p_through);
}

// A coat's weight seen at cosine `nv` from its normal: clearcoat * F_schlick(0.04, 1, N.V).
float coat_weight_at(float coat, float nv) {
    float m = 1.0 - clamp(nv, 0.0, 1.0);
    float m2 = m * m;
    return coat * (0.04 + 0.96 * m2 * m2 * m);
}

// Direction v (shading frame) in a frame around the coat's normal (z = coat_n).
vec3 to_coat(Surface s, vec3 v) {
    vec3 t;
    vec3 b;
    basis(s.coat_n, t, b);
    return vec3(dot(v, t), dot(v, b), dot(v, s.coat_n));
}

// Direction v of the coat's frame back in the shading frame.
vec3 from_coat(Surface s, vec3 v) {
    vec3 t;
    vec3 b;
    basis(s.coat_n, t, b);
    return v.x * t + v.y * b + v.z * s.coat_n;
}

// The coat's weight at wo.
float coat_weight(Surface s, vec3 wo) {
    return coat_weight_at(s.coat, dot(wo, s.coat_n));
}

// The coat's lobe (weight 1) for wo and wi: its GGX reflection about coat_n, where both lie
// above the coat and the shading frame. Its cosine is the coat's: the lobe is scaled by
// (coat_n.wi) / wi.z, as every caller multiplies f by the shading frame's |wi.z|.
float coat_reflection(Surface s, vec3 wo, vec3 wi) {
    vec3 o = to_coat(s, wo);
    vec3 i = to_coat(s, wi);
    if (!(wo.z > 0.0 && wi.z > 0.0 && o.z > 0.0 && i.z > 0.0)) {
        return 0.0;
    }
    vec3 h = normalize(o + i);
    return micro_d(h, s.coat_alpha) * micro_visibility(o, i, s.coat_alpha) * (i.z / wi.z);
}

// The density of the coat's sampling (micro_sample in its frame) of wi.
float coat_pdf(Surface s, vec3 wo, vec3 wi) {
    vec3 o = to_coat(s, wo);
    vec3 i = to_coat(s, wi);
    if (!(wo.z > 0.0 && wi.z > 0.0 && o.z > 0.0 && i.z > 0.0)) {
        return 0.0;
    }
    return micro_pdf(o, normalize(o + i), s.coat_alpha);
}

// The sheen lobe's directional albedo E(mu, roughness): the table bilinearly interpolated
// (src/sheen.rs's table_lookup).
float sheen_albedo(float mu, float roughness) {
    const float last = float(SHEEN_TABLE_SIZE - 1u);
    float x = sqrt(clamp(mu, 0.0, 1.0)) * last;
    float y = clamp(roughness, 0.0, 1.0) * last;
    uint i = min(uint(x), SHEEN_TABLE_SIZE - 2u);
    uint j = min(uint(y), SHEEN_TABLE_SIZE - 2u);
    float fx = x - float(i);
    float fy = y - float(j);
    // Entries k and k + 1 lie in one texel (i even) or in two.
    uint k = j * SHEEN_TABLE_SIZE + i;
    uint l = k + SHEEN_TABLE_SIZE;
    vec4 t0 = sheen_table_texel(k >> 2u);
    vec4 t1 = sheen_table_texel((k + 1u) >> 2u);
    vec4 t2 = sheen_table_texel(l >> 2u);
    vec4 t3 = sheen_table_texel((l + 1u) >> 2u);
    float a = mix(t0[k & 3u], t1[(k + 1u) & 3u], fx);
    float b = mix(t2[l & 3u], t3[(l + 1u) & 3u], fx);
    return mix(a, b, fy);
}

// The albedo scaling of the material under a sheen seen at cosine `nv` (one direction's term).
float sheen_scaling_at(Surface s, float nv) {
    return 1.0 - max3(s.sheen) * sheen_albedo(abs(nv), s.sheen_roughness);
}

float charlie_l(float x, float a) {
    float t = (1.0 - a) * (1.0 - a);
    return mix(21.5473, 25.3245, t) / (1.0 + mix(3.82987, 3.32435, t) * pow(x, mix(0.19823, 0.16801, t)))
           + mix(-1.97760, -1.27393, t) * x + mix(-4.32054, -4.85967, t);
}

float charlie_lambda(float c, float a) {
    return c < 0.5 ? exp(charlie_l(c, a)) : exp(2.0 * charlie_l(0.5, a) - charlie_l(1.0 - c, a));
}

// The sheen lobe (sheenColor 1) for wo and wi above the surface.
float sheen_lobe(Surface s, vec3 wo, vec3 wi) {
    float a = s.sheen_roughness * s.sheen_roughness;
    vec3 h = normalize(wo + wi);
    float d = (2.0 + 1.0 / a) * pow(max(1.0 - h.z * h.z, 0.0), 0.5 / a) * (0.5 * INV_PI);
    float denom = (1.0 + charlie_lambda(wo.z, a) + charlie_lambda(wi.z, a)) * 4.0 * wo.z * wi.z;
    return denom > 0.0 ? d / denom : 0.0;
}

// The material under the sheen, with the sheen (bsdf_eval_base when there is none).
vec3 bsdf_eval_sheened(Surface s, vec3 wo, vec3 wi) {
    vec3 f = bsdf_eval_base(s, wo, wi);
    if (max3(s.sheen) > 0.0) {
        f *= max(0.0, min(sheen_scaling_at(s, wo.z), sheen_scaling_at(s, wi.z)));
        if (wo.z > 0.0 && wi.z > 0.0) {
            f += s.sheen * sheen_lobe(s, wo, wi);
        }
    }
    return f;
}

// The probability of sampling the sheen's lobe among the material's: its share of the estimated
// albedo (the material's scaled by the scaling at wo).
float sheen_probability(Surface s, vec3 wo) {
    float e = max3(s.sheen) * sheen_albedo(wo.z, s.sheen_roughness);
    float base = max(0.0, 1.0 - e) * lobe_albedo_sum(lobe_albedos(s, wo));
    return e + base > 0.0 ? e / (e + base) : 0.0;
}

// The probability of sampling the coat's lobe: its share of the estimated albedo.
float coat_probability(Surface s, vec3 wo) {
    float w = coat_weight(s, wo);
    float a = lobe_albedo_sum(lobe_albedos(s, wo));
    float base = (1.0 - w) * a;
    if (max3(s.sheen) > 0.0) {
        float e = max3(s.sheen) * sheen_albedo(wo.z, s.sheen_roughness);
        base = (1.0 - w) * (e + max(0.0, 1.0 - e) * a);
    }
    return w + base > 0.0 ? w / (w + base) : 0.0;
}

vec3 bsdf_eval(Surface s, vec3 wo, vec3 wi) {
    vec3 f = bsdf_eval_sheened(s, wo, wi);
    if (s.coat > 0.0) {
        float w = coat_weight(s, wo);
        f *= 1.0 - w;
        f += vec3(w * coat_reflection(s, wo, wi));
    }
    return f;
}

// The diffuse lobes' part of bsdf_eval(s, wo, wi): bsdf_eval_base's Lambertian terms (reflection
// and KHR_materials_diffuse_transmission's) under the sheen's and the coat's scalings (the
// denoiser's lobe split, path.glsl).
vec3 bsdf_eval_diffuse(Surface s, vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z == 0.0) {
        return vec3(0.0);
    }
    vec3 f = vec3(0.0);
    if (wi.z < 0.0) {
        if (s.diffuse_transmission > 0.0) {
            f = bsdf_eval_diffuse_transmission(s, wo, wi);
        }
    } else {
        float oh = max(dot(wo, normalize(wo + wi)), 0.0);
        f = (1.0 - max3(dielectric_fresnel(s, oh))) * (1.0 - s.transmission) * s.base * INV_PI * (1.0 - s.metallic);
        if (s.diffuse_transmission > 0.0) {
            f *= 1.0 - s.diffuse_transmission;
        }
    }
    if (max3(s.sheen) > 0.0) {
        f *= max(0.0, min(sheen_scaling_at(s, wo.z), sheen_scaling_at(s, wi.z)));
    }
    if (s.coat > 0.0) {
        f *= 1.0 - coat_weight(s, wo);
    }
    return f;
}

// Solid-angle density of wi (below the surface) under the transmission lobe's sampling.
float transmission_pdf(Surface s, vec3 wo, vec3 wi) {
    if (s.thin) {
        vec3 wm = vec3(wi.xy, -wi.z);
        return spec_pdf(s, wo, normalize(wo + wm));
    }
    vec3 h = refraction_half_vector(s, wo, wi);
    float oh = dot(wo, h);
    float ih = dot(wi, h);
    if (oh <= 0.0 || ih >= 0.0) {
        return 0.0;
    }
    // Walter et al. 2007, eq. 17: |dh/dwi| = eta^2 |i.h| / (eta i.h + o.h)^2.
    float denom = s.eta * ih + oh;
    return spec_pdf_h(s, wo, h) * s.eta * s.eta * -ih / (denom * denom);
}

float bsdf_pdf_base(Surface s, vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z == 0.0) {
        return 0.0;
    }
    vec4 p = lobe_probabilities(s, wo);
    if (wi.z < 0.0) {
        float through = p.y > 0.0 ? p.y * transmission_pdf(s, wo, wi) : 0.0;
        if (s.diffuse_transmission > 0.0) {
            through += p.w * pdf_cosine_hemisphere(vec3(wi.xy, -wi.z));
        }
        return through;
    }
    vec3 h = normalize(wo + wi);
    return p.x * spec_pdf(s, wo, h) + p.z * pdf_cosine_hemisphere(wi);
}

// The density of the material's and the sheen's sampling (bsdf_pdf_base when there is no sheen).
float bsdf_pdf_sheened(Surface s, vec3 wo, vec3 wi) {
    float p = bsdf_pdf_base(s, wo, wi);
    if (max3(s.sheen) > 0.0) {
        float sheen = wo.z > 0.0 && wi.z > 0.0 ? pdf_cosine_hemisphere(wi) : 0.0;
        p = mix(p, sheen, sheen_probability(s, wo));
    }
    return p;
}

float bsdf_pdf(Surface s, vec3 wo, vec3 wi) {
    float p = bsdf_pdf_sheened(s, wo, wi);
    if (s.coat > 0.0) {
        p = mix(p, coat_pdf(s, wo, wi), coat_probability(s, wo));
    }
    return p;
}

// A direction from the base's lobes, picked by u.x; false when it leaves its lobe's side of the
// surface (or cannot refract). With SAMPLE_REUSE the lobe's share of u.x, stretched, replaces u.y.
bool bsdf_sample_base(Surface s, vec3 wo, vec3 u, out vec3 wi) {
    vec4 p = lobe_probabilities(s, wo);
    // The lobes' shares of u.x in order: specular reflection, transmission, diffuse, and
    // KHR_materials_diffuse_transmission's lobe last.
    bool reflects = u.x < p.x;
    bool refracts = !reflects && u.x < p.x + p.y;
    bool diffuse_through = false;
    if (s.diffuse_transmission > 0.0) {
        diffuse_through = u.x >= p.x + p.y + p.z;
    }
    if (SAMPLE_REUSE) {
        float lo = reflects ? 0.0 : (refracts ? p.x : (diffuse_through ? p.x + p.y + p.z : p.x + p.y));
        float share = reflects ? p.x : (refracts ? p.y : (diffuse_through ? p.w : p.z));
        u.y = stretch(u.x, lo, share);
    }
    if (reflects) {
        vec3 h = spec_sample(s, wo, u.yz);
        wi = reflect(-wo, h);
    } else if (refracts) {
        vec3 h = spec_sample(s, wo, u.yz);
        if (s.thin) {
            wi = reflect(-wo, h);
            wi.z = -wi.z;
        } else {
            wi = refract(-wo, h, 1.0 / s.eta);  // (0, 0, 0) beyond the critical angle
        }
        if (!(wi.z < 0.0)) {
            return false;
        }
    } else {
        wi = sample_cosine_hemisphere(u.yz);
        if (diffuse_through) {
            wi.z = -wi.z;
        }
    }
    return !(wi.z == 0.0 || (wi.z < 0.0 && !refracts && !diffuse_through));
}

// Samples wi; weight = f |cos| / pdf. False when the sample leaves its lobe's side of the surface
// (or cannot refract) or has no density.
bool bsdf_sample(Surface s, vec3 wo, vec3 u, out vec3 wi, out vec3 weight, out float pdf) {
    weight = vec3(0.0);
    pdf = 0.0;
    if (SAMPLE_REUSE) {
        // The lobe chosen by u.y, each lobe's share of it stretched back as its sample's u.y.
        u.x = u.y;
    }
    bool sampled;
    float q = 0.0;
    bool coat_lobe = false;
    if (s.coat > 0.0) {
        q = coat_probability(s, wo);
        coat_lobe = u.x < q;
    }
    if (coat_lobe) {
        if (SAMPLE_REUSE) {
            u.y = stretch(u.x, 0.0, q);
        }
        // Reflected in the coat's frame: a sample must lie above the coat and the shading frame
        // both, where coat_pdf counts it (with a tilted coat normal the two differ; a half
        // vector can reflect o below the coat where wi.z is still positive).
        vec3 o = to_coat(s, wo);
        vec3 i = reflect(-o, micro_sample(o, s.coat_alpha, u.yz));
        wi = from_coat(s, i);
        sampled = o.z > 0.0 && i.z > 0.0 && wi.z > 0.0;
    } else {
        if (s.coat > 0.0) {
            // The rest of u.x, stretched back over [0, 1).
            u.x = stretch(u.x, q, 1.0 - q);
        }
        bool sheen_lobe = false;
        if (max3(s.sheen) > 0.0) {
            float qs = sheen_probability(s, wo);
            sheen_lobe = u.x < qs;
            if (SAMPLE_REUSE && sheen_lobe) {
                u.y = stretch(u.x, 0.0, qs);
            }
            if (!sheen_lobe) {
                u.x = stretch(u.x, qs, 1.0 - qs);
            }
        }
        if (sheen_lobe) {
            wi = sample_cosine_hemisphere(u.yz);
            sampled = wi.z > 0.0;
        } else {
            sampled = bsdf_sample_base(s, wo, u, wi);
        }
    }
    if (!sampled) {
        return false;
    }
    pdf = bsdf_pdf(s, wo, wi);
    if (!(pdf > 0.0)) {
        return false;
    }
    weight = bsdf_eval(s, wo, wi) * abs(wi.z) / pdf;
    return true;
}

#endif
