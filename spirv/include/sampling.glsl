// Sampling routines, each with its pdf (Mitsuba's warp convention). Local frames have z along
// the normal.
#ifndef UMBRA_SAMPLING_GLSL
#define UMBRA_SAMPLING_GLSL

const float PI = 3.14159265358979323846;
const float INV_PI = 0.31830988618379067154;

// An orthonormal basis around unit n (Duff et al. 2017).
void basis(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

vec3 sample_cosine_hemisphere(vec2 u) {
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u.x)));
}

float pdf_cosine_hemisphere(vec3 w) {
    return max(w.z, 0.0) * INV_PI;
}

// A direction uniform in solid angle over the cone of half-angle θmax about +z, given
// 1 − cos θmax (a sun's few milliradians keep their precision that way; cos θmax itself would
// round to within 6e-8 of 1).
vec3 sample_uniform_cone(vec2 u, float one_minus_cos_max) {
    float omc = u.x * one_minus_cos_max;  // 1 - cos θ
    float sin_t = sqrt(max(omc * (2.0 - omc), 0.0));
    float phi = 2.0 * PI * u.y;
    return vec3(sin_t * cos(phi), sin_t * sin(phi), 1.0 - omc);
}

float pdf_uniform_cone(float one_minus_cos_max) {
    return 1.0 / (2.0 * PI * one_minus_cos_max);
}

// Uniform barycentrics (b1, b2) on a triangle.
vec2 sample_triangle(vec2 u) {
    float s = sqrt(u.x);
    return vec2(1.0 - s, u.y * s);
}

// ---- Spherical triangles: a triangle's solid angle, and directions uniform within it ----

// Solid angle of the spherical triangle with unit corners a, b, c (Van Oosterom and Strackee
// 1983: tan(Ω / 2) = |a·(b×c)| / (1 + a·b + b·c + c·a)).
float spherical_triangle_area(vec3 a, vec3 b, vec3 c) {
    return abs(2.0 * atan(dot(a, cross(b, c)), 1.0 + dot(a, b) + dot(a, c) + dot(b, c)));
}

// A direction uniform in solid angle within the spherical triangle with unit corners a, b, c and
// solid angle omega (spherical_triangle_area's), after Arvo (1995): u.x picks the sub-triangle
// (a, b, c') of solid angle u.x Ω, c' on the arc from a to c; u.y the point on the arc from b
// to c' (cos θ to b uniform). A smooth map of the unit square, so stratified numbers stay
// stratified. Arvo's construction reads the angle α at a as its cosine and sine (from the
// planes' normals) and Ω as given, never as a sum of angles from inverse trigonometry: GPU
// drivers approximate asin and acos (llvmpipe to about 1e-3), and a total that errs by a few
// thousandths of a small Ω leaves a sliver along the edge bc that no sample reaches. The caller
// keeps it to triangles whose solid angle is neither tiny nor near a hemisphere (SPHERICAL_MIN,
// SPHERICAL_MAX), where its arithmetic holds.
vec3 sample_spherical_triangle(vec3 a, vec3 b, vec3 c, float omega, vec2 u) {
    vec3 n_ab = normalize(cross(a, b));
    vec3 n_ac = normalize(cross(a, c));
    float cos_alpha = dot(n_ab, n_ac);
    float sin_alpha = length(cross(n_ab, n_ac));
    float area = u.x * omega;
    float sin_area = sin(area);
    float cos_area = cos(area);
    // s and t: the sine and cosine of the sub-triangle's area less α.
    float s = sin_area * cos_alpha - cos_area * sin_alpha;
    float t = cos_area * cos_alpha + sin_area * sin_alpha;
    float p = t - cos_alpha;
    float q = s + sin_alpha * dot(a, b);
    // The cosine of the arc from a to c'.
    float cos_ac = ((q * t - p * s) * cos_alpha - q) / ((q * s + p * t) * sin_alpha);
    cos_ac = clamp(cos_ac, -1.0, 1.0);
    vec3 cp = cos_ac * a + sqrt(max(0.0, 1.0 - cos_ac * cos_ac)) * normalize(c - dot(c, a) * a);
    float cos_theta = 1.0 - u.y * (1.0 - dot(cp, b));
    float sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    return cos_theta * b + sin_theta * normalize(cp - dot(cp, b) * b);
}

// The solid angles within which a triangle is sampled by solid angle: above SPHERICAL_MIN, a
// triangle over 8° across, where its 1/r² and cosine vary enough across it that area sampling's
// variance is worth removing (below, a point uniform on it is nearly uniform in solid angle, and
// the spherical triangle's arithmetic loses precision well before pbrt-v4's 3e-4); below
// SPHERICAL_MAX, away from a hemisphere, where the arc construction holds.
const float SPHERICAL_MIN = 0.2;
const float SPHERICAL_MAX = 6.22;

// ---- GGX (Trowbridge-Reitz), isotropic, alpha = roughness^2 ----

// D(h) = a^2 / (pi (sin^2 + a^2 cos^2)^2), with sin^2 as h.x^2 + h.y^2: the textbook
// cos^2 (a^2 - 1) + 1 cancels catastrophically for small a and goes to zero or negative once h's
// length rounds above 1 (approximate normalize on GPUs), giving Inf and then NaN.
float ggx_d(vec3 h, float a) {
    float a2 = a * a;
    float d = h.x * h.x + h.y * h.y + a2 * h.z * h.z;
    return h.z > 0.0 ? a2 / (PI * d * d) : 0.0;
}

// Smith G1 for GGX (separable form, as glTF Appendix B).
float ggx_g1(vec3 w, float a) {
    float c = abs(w.z);
    return 2.0 * c / (c + sqrt(a * a + (1.0 - a * a) * c * c));
}

// G1(w) / |w.z| for GGX, finite as w.z goes to 0 (where the quotient of the two would be 0/0
// once w.z * w.z flushes to zero).
float ggx_g1_over_cos(vec3 w, float a) {
    float c = abs(w.z);
    return 2.0 / (c + sqrt(a * a + (1.0 - a * a) * c * c));
}

// Density of the half vector h under sample_ggx_vndf(wo): G1(wo) max(0, wo.h) D(h) / wo.z.
float pdf_ggx_vndf(vec3 wo, vec3 h, float a) {
    return ggx_g1_over_cos(wo, a) * max(0.0, dot(wo, h)) * ggx_d(h, a);
}

// Half-vector sampling proportional to D(h) cos(theta_h) (Walter et al. 2007, eq. 35-36:
// tan^2(theta_h) = a^2 u / (1 - u)), blind to wo: half vectors facing away from wo are possible
// and have no density under micro_pdf (bsdf.glsl), so the caller discards them. cos and sin are
// taken from u directly (cos^2 = (1 - u) / (1 - u + a^2 u)), without 1 - cos^2, which would
// round to zero for small a.
vec3 sample_ggx_walter(float a, vec2 u) {
    float d = (1.0 - u.x) + a * a * u.x;
    float c = sqrt((1.0 - u.x) / d);
    float s = a * sqrt(u.x / d);
    float phi = 2.0 * PI * u.y;
    return vec3(s * cos(phi), s * sin(phi), c);
}

// Density of the half vector h under sample_ggx_walter: D(h) cos(theta_h).
float pdf_ggx_walter(vec3 h, float a) {
    return ggx_d(h, a) * max(h.z, 0.0);
}

// ---- GGX, anisotropic: alpha = (alpha_x, alpha_y) along the frame's x and y ----
// (Heitz 2014, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs"; the
// isotropic functions above are these with alpha_x = alpha_y, kept apart so that kernels without
// anisotropy compile to what they were.)

// D(h) = 1 / (pi ax ay ((hx / ax)^2 + (hy / ay)^2 + hz^2)^2).
float ggx_d_aniso(vec3 h, vec2 a) {
    vec2 s = h.xy / a;
    float d = dot(s, s) + h.z * h.z;
    return h.z > 0.0 ? 1.0 / (PI * a.x * a.y * d * d) : 0.0;
}

// G1(w) / |w.z| (Smith, separable): 2 / (|w.z| + sqrt(ax^2 wx^2 + ay^2 wy^2 + wz^2)).
float ggx_g1_over_cos_aniso(vec3 w, vec2 a) {
    vec2 s = a * w.xy;
    return 2.0 / (abs(w.z) + sqrt(dot(s, s) + w.z * w.z));
}

// Visible-normal sampling for anisotropic GGX (Heitz 2018: the view stretched by (ax, ay) to
// the hemisphere configuration, a visible normal sampled there, stretched back).
vec3 sample_ggx_vndf_aniso(vec3 wo, vec2 a, vec2 u) {
    vec3 vh = normalize(vec3(a * wo.xy, wo.z));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = lensq > 0.0 ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(lensq) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    float p1 = r * cos(phi);
    float p2 = r * sin(phi);
    float s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * p2;
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    return normalize(vec3(a * nh.xy, max(1e-7, nh.z)));
}

// Visible-normal sampling (Heitz 2018, "Sampling the GGX Distribution of Visible Normals"): the
// isotropic case.
vec3 sample_ggx_vndf(vec3 wo, float a, vec2 u) {
    return sample_ggx_vndf_aniso(wo, vec2(a), u);
}

// Density of the half vector h under sample_ggx_vndf_aniso(wo): G1(wo) max(0, wo.h) D(h) / wo.z.
float pdf_ggx_vndf_aniso(vec3 wo, vec3 h, vec2 a) {
    return ggx_g1_over_cos_aniso(wo, a) * max(0.0, dot(wo, h)) * ggx_d_aniso(h, a);
}

// ---- Beckmann, alpha = roughness^2 ----

float beckmann_d(vec3 h, float a) {
    if (h.z <= 0.0) {
        return 0.0;
    }
    float c2 = h.z * h.z;
    float tan2 = (h.x * h.x + h.y * h.y) / c2;  // not (1 - c2) / c2: see ggx_d
    return exp(-tan2 / (a * a)) / (PI * a * a * c2 * c2);
}

// Smith G1 for Beckmann, Walter et al. 2007's rational approximation, divided by |w.z|
// (finite as w.z goes to 0): with b = cot(theta) / a, G1 = b (3.535 + 2.181 b) / (1 + 2.276 b +
// 2.577 b^2) below b = 1.6, and 1 above.
float beckmann_g1_over_cos(vec3 w, float a) {
    float c = abs(w.z);
    float s = sqrt(w.x * w.x + w.y * w.y);
    if (c >= 1.6 * a * s) {
        return 1.0 / c;
    }
    float b = c / (a * s);
    return (3.535 + 2.181 * b) / (a * s * (1.0 + 2.276 * b + 2.577 * b * b));
}

float beckmann_g1(vec3 w, float a) {
    return beckmann_g1_over_cos(w, a) * abs(w.z);
}

// Half-vector sampling proportional to D(h) cos(theta_h) (Walter et al. 2007, eq. 28-29).
vec3 sample_beckmann(float a, vec2 u) {
    float tan2 = -a * a * log(1.0 - u.x);
    float c = inversesqrt(1.0 + tan2);
    float s = sqrt(max(0.0, 1.0 - c * c));
    float phi = 2.0 * PI * u.y;
    return vec3(s * cos(phi), s * sin(phi), c);
}

float pdf_beckmann(vec3 h, float a) {
    return beckmann_d(h, a) * max(h.z, 0.0);
}

#endif
