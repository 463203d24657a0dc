#version 460
// Denoiser step 2 (src/passes/denoise.rs): one iteration of the edge-avoiding à-trous wavelet
// filter of SVGF (Schied et al. 2017, its spatial part; Dammertz et al. 2010). Taps on a 3×3 grid
// `params.step` pixels apart weighted by (1/4, 1/2, 1/4) in x and y, or with DENOISE_WIDE on a
// 5×5 grid by the B3 spline (1/16, 1/4, 3/8, 1/4, 1/16), times, with DENOISE_EDGE_STOPPING:
// - normal: max(0, n·n')^sigma_normal;
// - depth: exp(−|z − z'| / (sigma_depth (|∇z · offset| + 1e-3 z))), ∇z the smaller one-sided
//   difference along each axis (so a silhouette next to the pixel does not widen it);
// - luminance: exp(−|l − l'| / (sigma_luminance √var + 1e-6)), var the variance of the centre's
//   luminance, through a 3×3 Gaussian with DENOISE_PREFILTER (a few samples' variance is noisy);
// - a pixel that saw no surface mixes only with such pixels, by luminance.
// The variance is carried along with the squared weights: var' = Σ w² var / (Σ w)².
// With DENOISE_BOTH it filters two images at once (the lobe split's diffuse and specular parts,
// each by its own luminance and variance), the taps' normal and depth weights computed once: the
// same results as two dispatches, for one pass over the guide.
#extension GL_GOOGLE_include_directive : require
#include "kernel/denoise_atrous.glsl"
#include "denoise.glsl"

KERNEL_LOCAL_SIZE;

ivec2 size;

bool inside(ivec2 q) {
    return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, size));
}

// The smaller one-sided difference of the distance along `axis` (0 where neither neighbour is a
// surface inside the image).
float depth_slope(ivec2 pixel, float z, ivec2 axis) {
    float slope = 1e30;
    for (int side = -1; side <= 1; side += 2) {
        ivec2 q = pixel + side * axis;
        if (inside(q)) {
            float zq = imageLoad(dn_guide, q).w;
            if (zq >= 0.0) {
                slope = min(slope, abs(zq - z));
            }
        }
    }
    return slope < 1e30 ? slope : 0.0;
}

// One image's filter state: the centre's colour and luminance, the luminance weight's scale,
// and the taps' sums.
struct Lobe {
    vec4 c0;
    float l0;
    float var;
    float inv_l;
    vec3 sum;
    float var_sum;
    float w2_sum;
    float weight;
};

Lobe lobe_start(vec4 c0) {
    return Lobe(c0, dot(DENOISE_LUMA, c0.rgb), c0.a, 0.0, vec3(0.0), 0.0, 0.0, 0.0);
}

// Adds tap colour `c` with base weight `w` (the spline's, times the normal weight) and depth
// term `e_depth` (0 without edge stopping or at a miss).
void lobe_tap(inout Lobe lobe, vec4 c, float w, float e_depth, bool edges) {
    if (edges) {
        float e = abs(dot(DENOISE_LUMA, c.rgb) - lobe.l0) * lobe.inv_l;
        e += e_depth;
        w *= exp(-e);
    }
    if (!(w > 0.0) || any(isnan(c)) || any(isinf(c))) {
        return;
    }
    lobe.sum += w * c.rgb;
    lobe.var_sum += w * w * c.a;
    lobe.w2_sum += w * w;
    lobe.weight += w;
}

// The filtered colour and variance (the centre's own where no tap counted).
vec4 lobe_result(Lobe lobe, bool spatial) {
    // The centre always counts (weight 9/64 or 1/4): `weight` is never 0 for a finite centre.
    vec4 result = lobe.weight > 0.0 ? vec4(lobe.sum / lobe.weight, lobe.var_sum / (lobe.weight * lobe.weight))
                                    : lobe.c0;
    if (spatial && lobe.weight > 0.0) {
        // What the taps' own variances left out (1 spp: they are 0): the variance the weights
        // used, as if every tap had it.
        result.a = max(result.a, lobe.var * lobe.w2_sum / (lobe.weight * lobe.weight));
    }
    return result;
}

// The 3×3 neighbourhood's spread of luminance on the same surface: w_sum, Σ w l, Σ w l².
void spread_add(inout vec3 spread, float w, float l) {
    if (w > 0.0 && !isnan(l) && !isinf(l)) {
        spread += vec3(w, w * l, w * l * l);
    }
}

// The first iteration's variance floor from the spread (see main).
float spread_floor(float var, vec3 spread, float samples) {
    if (spread.x > 0.0) {
        float mean_l = spread.y / spread.x;
        var = max(var, (spread.z / spread.x - mean_l * mean_l) * min(1.0, 4.0 / samples));
    }
    return var;
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    size = ivec2(params.size);
    if (!inside(pixel)) {
        return;
    }
    bool both = (params.flags & DENOISE_BOTH) != 0u;
    Lobe a = lobe_start(imageLoad(dn_in, pixel));
    Lobe b = lobe_start(both ? imageLoad(dn_in2, pixel) : vec4(0.0));
    vec4 g0 = imageLoad(dn_guide, pixel);
    bool edges = (params.flags & DENOISE_EDGE_STOPPING) != 0u;
    bool hit0 = g0.w >= 0.0;

    if ((params.flags & DENOISE_PREFILTER) != 0u) {
        vec2 sum = vec2(0.0);
        float weight = 0.0;
        for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
                ivec2 q = pixel + ivec2(dx, dy);
                if (inside(q)) {
                    float w = (dx == 0 ? 0.5 : 0.25) * (dy == 0 ? 0.5 : 0.25);
                    sum.x += w * imageLoad(dn_in, q).a;
                    if (both) {
                        sum.y += w * imageLoad(dn_in2, q).a;
                    }
                    weight += w;
                }
            }
        }
        a.var = sum.x / weight;
        b.var = sum.y / weight;
    }
    vec2 slope = hit0 ? vec2(depth_slope(pixel, g0.w, ivec2(1, 0)), depth_slope(pixel, g0.w, ivec2(0, 1)))
                      : vec2(0.0);
    float z_eps = 1e-3 * g0.w;
    bool spatial = edges && (params.flags & DENOISE_SPATIAL_VARIANCE) != 0u && params.step == 1u;
    if (spatial) {
        // The first iteration: a few samples' variance can be 0 where every sample happened to
        // agree (a penumbra whose samples all missed the light). The spread of the neighbours'
        // luminance on the same surface (normal and depth weights, 3×3) bounds it from below,
        // fully up to 4 samples, then fading as 4 / samples: the spread holds the signal's own
        // variation too, which more samples do not shrink, while the pixel's own estimate
        // becomes reliable (SVGF likewise estimates spatially for its first 4 frames only).
        vec3 spread_a = vec3(0.0);
        vec3 spread_b = vec3(0.0);
        for (int j = -1; j <= 1; ++j) {
            for (int i = -1; i <= 1; ++i) {
                ivec2 q = pixel + ivec2(i, j);
                if (!inside(q)) {
                    continue;
                }
                vec4 g = imageLoad(dn_guide, q);
                if ((g.w >= 0.0) != hit0) {
                    continue;
                }
                float w = 1.0;
                if (hit0) {
                    w = pow(max(dot(g0.xyz, g.xyz), 0.0), params.sigma_normal);
                    float along = abs(slope.x * float(i)) + abs(slope.y * float(j));
                    w *= exp(-abs(g.w - g0.w) / (params.sigma_depth * (along + z_eps)));
                }
                spread_add(spread_a, w, dot(DENOISE_LUMA, imageLoad(dn_in, q).rgb));
                if (both) {
                    spread_add(spread_b, w, dot(DENOISE_LUMA, imageLoad(dn_in2, q).rgb));
                }
            }
        }
        float samples = max(imageLoad(dn_samples, pixel).x, 1.0);
        a.var = spread_floor(a.var, spread_a, samples);
        b.var = spread_floor(b.var, spread_b, samples);
    }
    a.inv_l = 1.0 / (params.sigma_luminance * sqrt(max(a.var, 0.0)) + 1e-6);
    b.inv_l = 1.0 / (params.sigma_luminance * sqrt(max(b.var, 0.0)) + 1e-6);

    const float spline[5] = float[5](1.0 / 16.0, 1.0 / 4.0, 3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);
    const float tent[3] = float[3](1.0 / 4.0, 1.0 / 2.0, 1.0 / 4.0);
    bool wide = (params.flags & DENOISE_WIDE) != 0u;
    int r = wide ? 2 : 1;
    int step = int(params.step);
    for (int j = -r; j <= r; ++j) {
        for (int i = -r; i <= r; ++i) {
            ivec2 offset = ivec2(i, j) * step;
            ivec2 q = pixel + offset;
            if (!inside(q)) {
                continue;
            }
            float w = wide ? spline[i + 2] * spline[j + 2] : tent[i + 1] * tent[j + 1];
            float e_depth = 0.0;
            if (edges) {
                vec4 g = imageLoad(dn_guide, q);
                bool hit = g.w >= 0.0;
                if (hit != hit0) {
                    continue;
                }
                if (hit0) {
                    w *= pow(max(dot(g0.xyz, g.xyz), 0.0), params.sigma_normal);
                    float along = abs(slope.x * float(offset.x)) + abs(slope.y * float(offset.y));
                    e_depth = abs(g.w - g0.w) / (params.sigma_depth * (along + z_eps));
                }
            }
            lobe_tap(a, imageLoad(dn_in, q), w, e_depth, edges);
            if (both) {
                lobe_tap(b, imageLoad(dn_in2, q), w, e_depth, edges);
            }
        }
    }
    imageStore(dn_out, pixel, lobe_result(a, spatial));
    if (both) {
        imageStore(dn_out2, pixel, lobe_result(b, spatial));
    }
}
