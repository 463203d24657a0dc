// Shadow-map visibility of a punctual light at a shaded point (deferred.comp): the light's
// record and layers in `shadow_texels` (src/passes/shadow.rs writes them), depth in
// `shadow_depth`, filtered moments in `shadow_moments`. The filter is the kernel's
// specialization: hard (the nearest texel), PCF (16 rotated Poisson taps, each a bilinear
// compare), PCSS (a blocker search, the penumbra from the light's size, then PCF of that
// radius) or moments (Hamburger 4MSM, Peters and Klein 2015).
//
// Biases, all in texels of the layer at the receiver (so one setting suits every resolution and
// distance): the point moves along its geometric normal by `normal` texels, the compared depth is
// lowered by `constant + slope · tan θ` texels (θ between normal and light, tan θ at most 10),
// and each texel a filter compares is compared with the receiver's plane at that texel
// (receiver-plane depth bias), not with the depth at the filter's centre.
#ifndef UMBRA_SHADOW_GLSL
#define UMBRA_SHADOW_GLSL

#include "shadow_layers.glsl"

float shadow_map_depth(ShadowLayer l, ivec2 q) {
    q = clamp(q, ivec2(0), ivec2(int(l.size) - 1));
    return imageLoad(shadow_depth, int(l.offset + uint(q.y) * l.size + uint(q.x))).x;
}

// The receiver's plane (through the shaded point, normal ng) as a depth over the layer's texels
// around it: depth(centre + o) = d + dot(g, o) (receiver-plane depth bias, Isidoro 2006), so each
// compared texel is compared with the receiver's depth at that texel, not at its centre. From
// the Jacobian of (x, y, depth) along two tangents of the plane at the receiver, which the
// layer places at texel `uv` with divisor `w`; the gradient is limited to `limit` depth per texel
// (the plane seen edge-on has none).
vec2 shadow_receiver_gradient(ShadowLayer l, vec2 uv, float w, vec3 ng, float limit) {
    vec3 t1 = normalize(cross(ng, abs(ng.x) > 0.5 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0)));
    vec3 t2 = cross(ng, t1);
    vec3 j1 = vec3((dot(l.row0.xyz, t1) - uv.x * dot(l.row3.xyz, t1)) / w,
                   (dot(l.row1.xyz, t1) - uv.y * dot(l.row3.xyz, t1)) / w, dot(l.row2.xyz, t1));
    vec3 j2 = vec3((dot(l.row0.xyz, t2) - uv.x * dot(l.row3.xyz, t2)) / w,
                   (dot(l.row1.xyz, t2) - uv.y * dot(l.row3.xyz, t2)) / w, dot(l.row2.xyz, t2));
    float det = j1.x * j2.y - j1.y * j2.x;
    vec2 g = vec2(j1.z * j2.y - j1.y * j2.z, j1.x * j2.z - j1.z * j2.x) / det;
    float len = length(g);
    return isnan(len) || isinf(len) ? vec2(0.0) : g * min(1.0, limit / max(len, 1e-30));
}

// The compared depth of the receiver at texel `texel` (integer coordinates): its plane's depth
// at the texel's centre.
float shadow_receiver_at(ivec2 texel, vec2 uv, float d, vec2 g) {
    return d + dot(g, vec2(texel) + 0.5 - uv);
}

// 1 where the stored depth is at or beyond the receiver's compared depth, bilinear over the four
// texels around `tap` (texel units): a compare per texel, each with the receiver plane's depth
// there (centre uv, depth d, gradient g), then the weights.
float shadow_compare_bilinear(ShadowLayer l, vec2 tap, vec2 uv, float d, vec2 g) {
    vec2 c = tap - 0.5;
    ivec2 q = ivec2(floor(c));
    vec2 f = c - vec2(q);
    vec4 lit;
    for (int k = 0; k < 4; ++k) {
        ivec2 t = q + ivec2(k & 1, k >> 1);
        lit[k] = step(shadow_receiver_at(t, uv, d, g), shadow_map_depth(l, t));
    }
    return mix(mix(lit.x, lit.y, f.x), mix(lit.z, lit.w, f.x), f.y);
}

const vec2 SHADOW_POISSON[16] = vec2[](
    vec2(-0.94201624, -0.39906216), vec2(0.94558609, -0.76890725), vec2(-0.094184101, -0.92938870),
    vec2(0.34495938, 0.29387760), vec2(-0.91588581, 0.45771432), vec2(-0.81544232, -0.87912464),
    vec2(-0.38277543, 0.27676845), vec2(0.97484398, 0.75648379), vec2(0.44323325, -0.97511554),
    vec2(0.53742981, -0.47373420), vec2(-0.26496911, -0.41893023), vec2(0.79197514, 0.19090188),
    vec2(-0.24188840, 0.99706507), vec2(-0.81409955, 0.91437590), vec2(0.19984126, 0.78641367),
    vec2(0.14383161, -0.14100790));

// The 16 Poisson taps of radius r (texels) around uv, rotated by `rotation` (a 2×2 matrix).
float shadow_pcf(ShadowLayer l, vec2 uv, float d, vec2 g, float r, mat2 rotation) {
    float sum = 0.0;
    for (uint i = 0u; i < 16u; ++i) {
        sum += shadow_compare_bilinear(l, uv + r * (rotation * SHADOW_POISSON[i]), uv, d, g);
    }
    return sum * (1.0 / 16.0);
}

// Hamburger 4MSM (Peters and Klein 2015, algorithm 2): the shadow intensity (fraction of the
// filter region in front of depth z) bounded from the four moments b, biased towards those of
// two equal spikes at 0 and 1, (0.5, 0.5, 0.5, 0.5), by `alpha` for stability.
float shadow_msm_intensity(vec4 b, float z, float alpha) {
    b = mix(b, vec4(0.5), alpha);
    float l32_d22 = -b.x * b.y + b.z;
    float d22 = -b.x * b.x + b.y;
    float squared_depth_variance = -b.y * b.y + b.w;
    float d33_d22 = dot(vec2(squared_depth_variance, -l32_d22), vec2(d22, l32_d22));
    float inv_d22 = 1.0 / d22;
    float l32 = l32_d22 * inv_d22;
    vec3 c = vec3(1.0, z, z * z);
    c.y -= b.x;
    c.z -= b.y + l32 * c.y;
    c.y *= inv_d22;
    c.z *= d22 / d33_d22;
    c.y -= l32 * c.z;
    c.x -= dot(c.yz, b.xy);
    float p = c.y / c.z;
    float q = c.x / c.z;
    float root = sqrt(max(p * p * 0.25 - q, 0.0));
    float z1 = -p * 0.5 - root;
    float z2 = -p * 0.5 + root;
    vec4 switch_ = z2 < z ? vec4(z1, z, 1.0, 1.0) : (z1 < z ? vec4(z, z1, 0.0, 1.0) : vec4(0.0));
    float quotient = (switch_.x * z2 - b.x * (switch_.x + z2) + b.y) / ((z2 - switch_.y) * (z - z1));
    return clamp(switch_.z + switch_.w * quotient, 0.0, 1.0);
}

// Light k's layer that sees p (a cube's face by the major axis from the light, a cascade by the
// view depth along `view_forward` from `view_origin`); false for a light without maps or a point
// beyond the last cascade (`lit` says which).
bool shadow_pick_layer(uint k, vec3 p, vec3 view_origin, vec3 view_forward, out ShadowLayer layer, out bool lit) {
    uvec4 rec = imageLoad(shadow_texels, int(SHADOW_HEADER_TEXELS + k));
    lit = false;
    if (rec.z == SHADOW_LIGHT_NONE) {
        return false;
    }
    uint first = rec.x;
    if (rec.z == SHADOW_LIGHT_CUBE) {
        vec3 v = p - punctual_vec(k, 0u).xyz;
        vec3 a = abs(v);
        uint face = a.x >= a.y && a.x >= a.z ? (v.x > 0.0 ? 0u : 1u)
                  : (a.y >= a.z ? (v.y > 0.0 ? 2u : 3u) : (v.z > 0.0 ? 4u : 5u));
        first += SHADOW_LAYER_TEXELS * face;
    } else if (rec.z == SHADOW_LIGHT_CASCADES) {
        float depth = dot(p - view_origin, view_forward);
        uint j = 0u;
        while (j + 1u < rec.y && shadow_header(first + SHADOW_LAYER_TEXELS * j + 5u).z < depth) {
            ++j;
        }
        first += SHADOW_LAYER_TEXELS * j;
        if (shadow_header(first + 5u).z < depth) {
            lit = true;
            return false;
        }
    }
    layer = shadow_layer(first);
    return true;
}

// Visibility in [0, 1] of punctual light k (direction wi towards it) at p, whose geometric normal
// ng faces the light's side, from its shadow map (every punctual light has one when the kernel
// has maps; beyond the last cascade is lit). `pixel` rotates the filter taps.
float shadow_map_visibility(uint k, vec3 p, vec3 ng, vec3 wi, vec3 view_origin, vec3 view_forward, uvec2 pixel) {
    ShadowLayer l;
    bool lit;
    if (!shadow_pick_layer(k, p, view_origin, view_forward, l, lit)) {
        return 1.0;
    }
    vec4 bias = shadow_header(0u);   // constant, slope, normal (texels), PCF radius (texels)
    vec4 soft = shadow_header(1u);   // light radius (m), tan(sun's angular radius), max radius, moment bias
    vec4 p1 = vec4(p, 1.0);
    float depth0 = dot(l.row3, p1);
    float texel = l.kind == SHADOW_PERSPECTIVE ? l.texel_world * max(depth0, 0.0) : l.texel_world;
    float cos_t = clamp(abs(dot(ng, wi)), 1e-4, 1.0);
    float tan_t = min(sqrt(1.0 - cos_t * cos_t) / cos_t, 10.0);
    vec4 q = vec4(p + ng * (bias.z * texel), 1.0);
    vec4 h = vec4(dot(l.row0, q), dot(l.row1, q), dot(l.row2, q), dot(l.row3, q));
    if (h.w <= 0.0) {
        return 1.0;
    }
    vec2 uv = h.xy / h.w;
    float d = h.z - texel * (bias.x + bias.y * tan_t);
    if (SHADOW_MOMENTS) {
        vec2 corner = uv - 0.5;
        ivec2 c = clamp(ivec2(floor(corner)), ivec2(0), ivec2(int(l.size) - 2));
        vec2 f = clamp(corner - vec2(c), 0.0, 1.0);
        int i = int(l.offset) + c.y * int(l.size) + c.x;
        vec4 m = mix(mix(imageLoad(shadow_moments, i), imageLoad(shadow_moments, i + 1), f.x),
                     mix(imageLoad(shadow_moments, i + int(l.size)), imageLoad(shadow_moments, i + int(l.size) + 1), f.x),
                     f.y);
        return 1.0 - shadow_msm_intensity(m, clamp(d / l.depth_far, 0.0, 1.0), soft.w);
    }
    // Spec constants only as plain `if` conditions (`!A && !B` on them would be an
    // OpSpecConstantOp, which naga rejects).
    vec2 g = shadow_receiver_gradient(l, uv, h.w, ng, 10.0 * texel);
    bool filtered = false;
    if (SHADOW_PCF) {
        filtered = true;
    }
    if (SHADOW_PCSS) {
        filtered = true;
    }
    if (!filtered) {
        ivec2 t = ivec2(floor(uv));
        return step(shadow_receiver_at(t, uv, d, g), shadow_map_depth(l, t));
    }
    float angle = 6.2831853 * float(pcg4d(uvec4(pixel, k, 0x5eedu)).x >> 8) * (1.0 / 16777216.0);
    mat2 rotation = mat2(cos(angle), sin(angle), -sin(angle), cos(angle));
    float radius = bias.w;
    if (SHADOW_PCSS) {
        // Blocker search over the region where blockers can shade p (the penumbra a blocker
        // halfway to the light would cast), then the penumbra from the blockers' mean depth.
        bool perspective = l.kind == SHADOW_PERSPECTIVE;
        float search = min(perspective ? soft.x / texel : h.z * soft.y / texel, soft.z);
        float blockers = 0.0;
        float found = 0.0;
        for (uint i = 0u; i < 16u; ++i) {
            ivec2 t = ivec2(floor(uv + search * (rotation * SHADOW_POISSON[i])));
            float z = shadow_map_depth(l, t);
            if (z < shadow_receiver_at(t, uv, d, g)) {
                blockers += z;
                found += 1.0;
            }
        }
        if (found == 0.0) {
            return 1.0;
        }
        float blocker = blockers / found;
        float penumbra = perspective ? soft.x * (h.z - blocker) / max(blocker, 1e-6) : (h.z - blocker) * soft.y;
        radius = clamp(penumbra / texel, 0.5, soft.z);
    }
    return shadow_pcf(l, uv, d, g, radius, rotation);
}

// Ray-traced shadows of a sized punctual light (the reference the map filters' soft shadows are
// charted against): the fraction of `rays` shadow rays from p that reach the light unoccluded.
// A point or spot light is a sphere of `radius` around its position: the rays go uniformly in
// solid angle over the cone the sphere subtends at p (a uniformly bright sphere looks like a
// uniformly bright disc from anywhere, so its visible fraction is the unoccluded fraction of that
// solid angle; points uniform on the sphere's surface would weigh the disc's rim too much) and
// stop at the sphere's near surface. A directional light is the cone of directions with
// 1 − cos of its angular radius `sun_omc`. The light's radiance term stays the centre's: only
// visibility is averaged. Directions below the surface (ng, facing the light's side) count as
// occluded by it. The rays' directions follow the R2 sequence (Roberts 2018) from index
// frame × rays on, rotated per pixel and light (Cranley-Patterson), so successive frames continue
// one stratified sequence. With radius and angle 0 every ray is the point light's one shadow ray.
const uint RNG_SIZED_LIGHT = 64u;  // + the light's index: the per-pixel rotation

float sized_light_visibility(uint k, vec3 p, vec3 ng, vec3 wi, bool to_point, vec3 position, float radius,
                             float sun_omc, uint rays, uint frame, uint seed, uvec2 pixel) {
    float omc = sun_omc;
    vec3 to_light = position - p;
    float d2 = dot(to_light, to_light);
    if (to_point) {
        // sin² of the cone's half-angle; a point inside the sphere sees the hemisphere towards its
        // centre (a light is not meant to enclose a shaded surface).
        float s2 = min(radius * radius / d2, 1.0);
        omc = s2 / (1.0 + sqrt(1.0 - s2));
    }
    vec3 t;
    vec3 b;
    basis(wi, t, b);
    vec2 rotation = rand4(pixel, 0u, RNG_SIZED_LIGHT + k, seed).xy;
    vec3 o = offset_ray(p, ng);
    float lit = 0.0;
    for (uint r = 0u; r < rays; ++r) {
        uint i = frame * rays + r;
        // R2: i × (1/φ₂, 1/φ₂²) in 32-bit fixed point, wrapping exactly.
        vec2 u = fract(rotation + vec2(uvec2(i * 3242174889u, i * 2447445413u) >> 8u) * (1.0 / 16777216.0));
        vec3 c = sample_uniform_cone(u, omc);
        vec3 dir = omc > 0.0 ? t * c.x + b * c.y + wi * c.z : wi;
        vec3 target = position;
        if (to_point && radius > 0.0) {
            // The sphere's near surface along dir.
            float along = dot(dir, to_light);
            float near = along - sqrt(max(radius * radius - (d2 - along * along), 0.0));
            vec3 m = p + dir * near - position;
            target = position + radius * (m / max(length(m), 1e-30));
        }
        if (dot(dir, ng) > 0.0 && !bvh_any(o, to_point ? target - o : dir, 0.0, to_point ? 0.9999 : BVH_INF)) {
            lit += 1.0;
        }
    }
    return lit / float(rays);
}

#endif
