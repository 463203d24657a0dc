// The shadow rasterizer's shared part (shadow_bin.comp, shadow_raster.comp): a triangle's
// vertices in a layer's homogeneous texel space, the tiles and texels its box can touch, its
// edge functions and the coverage and depth test of a texel centre, so both kernels decide
// every texel alike.
//
// Vertices are transformed by the layer's rows into (X, Y, D, W) = (x w, y w, depth, w), x and y
// in texels. Coverage is homogeneous (Olano and Greer 1997): a texel centre (px, py) is covered
// when (px, py, 1) is a positive combination of the three (X, Y, W), so no clipping is needed for
// vertices behind a perspective light (w ≤ 0). The edge function of edge (a, b) is
// cross(a, b) · (px, py, 1) over (X, Y, W). A shared edge gives its two triangles exactly negated
// coefficients (the cross product of the same two vectors in the other order, the same vertices
// transformed by the same operations), and once each triangle is oriented by its determinant's
// sign the two evaluate exactly negated values: a texel centre is inside one of them or on the
// edge of both, where the tie rule (coefficient a > 0, or a = 0 and b > 0) gives it to exactly
// one. No cracks, no double hits, whatever the winding. Depth is the linear depth interpolated
// with the homogeneous barycentrics, clamped at 0 (casters between the light and the near plane
// still cast: "pancaking").
#ifndef UMBRA_SHADOW_RASTER_GLSL
#define UMBRA_SHADOW_RASTER_GLSL

#include "shadow_pack.glsl"

// Vertex k of BVH triangle `tri` in the layer's homogeneous texel space.
vec4 shadow_vertex(uint tri, uint k) {
    vec4 p = vec4(bvh_tri_v(tri, k).xyz, 1.0);
    return vec4(dot(params.row0, p), dot(params.row1, p), dot(params.row2, p), dot(params.row3, p));
}

// The texel box (x0, y0, x1, y1, inclusive) of the texel centres a triangle can cover, and
// whether it is bounded (every vertex in front: w > 0; otherwise the whole window), clipped to
// the layer's window (ShadowRasterParams::window_lo, window_hi); false when it covers none.
bool shadow_texel_box(vec4 v0, vec4 v1, vec4 v2, out uvec4 box, out bool bounded) {
    float s = float(params.size);
    // Wholly outside one plane of the layer's pyramid (x ≥ 0, x ≤ size w, same for y, w > 0):
    // the whole positive cone of the three vertices is outside, whatever their w.
    bvec3 out_x0 = lessThan(vec3(v0.x, v1.x, v2.x), vec3(0.0));
    bvec3 out_x1 = greaterThan(vec3(v0.x, v1.x, v2.x), s * vec3(v0.w, v1.w, v2.w));
    bvec3 out_y0 = lessThan(vec3(v0.y, v1.y, v2.y), vec3(0.0));
    bvec3 out_y1 = greaterThan(vec3(v0.y, v1.y, v2.y), s * vec3(v0.w, v1.w, v2.w));
    bvec3 out_w = lessThanEqual(vec3(v0.w, v1.w, v2.w), vec3(0.0));
    if (all(out_x0) || all(out_x1) || all(out_y0) || all(out_y1) || all(out_w)) {
        return false;
    }
    bounded = !any(out_w);
    // The layer's window (the tiles rendered): the box never leaves it.
    uvec2 w_lo = shadow_unpack(params.window_lo) * SHADOW_TILE;
    uvec2 w_hi = min((shadow_unpack(params.window_hi) + 1u) * SHADOW_TILE, uvec2(params.size)) - 1u;
    box = uvec4(w_lo, w_hi);
    if (bounded) {
        // Texel centres x + 0.5 within the projected box, a texel wider each side against the
        // division's rounding (the edge functions decide).
        vec2 a = v0.xy / v0.w;
        vec2 b = v1.xy / v1.w;
        vec2 c = v2.xy / v2.w;
        vec2 lo = clamp(floor(min(a, min(b, c)) - 0.5), vec2(0.0), vec2(s - 1.0));
        vec2 hi = clamp(ceil(max(a, max(b, c)) - 0.5), vec2(0.0), vec2(s - 1.0));
        box = uvec4(max(uvec2(lo), w_lo), min(uvec2(hi), w_hi));
    }
    return all(lessThanEqual(box.xy, box.zw));
}

// The oriented edge functions of a triangle; false when it is edge-on to the light (it covers
// no texel centre).
bool shadow_edges(vec4 a, vec4 b, vec4 c, out vec3 e0, out vec3 e1, out vec3 e2) {
    precise vec3 c0 = cross(b.xyw, c.xyw);
    precise vec3 c1 = cross(c.xyw, a.xyw);
    precise vec3 c2 = cross(a.xyw, b.xyw);
    precise float det = dot(a.xyw, c0);
    float sign_ = det > 0.0 ? 1.0 : -1.0;
    e0 = c0 * sign_;
    e1 = c1 * sign_;
    e2 = c2 * sign_;
    return !(det == 0.0 || isnan(det) || isinf(det));
}

// Whether an oriented edge function's value at a texel centre counts as inside (the tie rule on
// zero).
bool shadow_edge_inside(vec3 e, float value) {
    return value > 0.0 || (value == 0.0 && (e.x > 0.0 || (e.x == 0.0 && e.y > 0.0)));
}

// Whether oriented edge e is negative at all four corners of the box [lo, hi] (so at every
// point of it: no texel centre inside the box is covered).
bool shadow_edge_outside(vec3 e, vec2 lo, vec2 hi) {
    vec4 x = vec4(lo.x, hi.x, lo.x, hi.x);
    vec4 y = vec4(lo.y, lo.y, hi.y, hi.y);
    return all(lessThan(e.x * x + e.y * y + e.z, vec4(0.0)));
}

// Whether the triangle with oriented edges e0..e2 and vertex depths d covers the centre of
// texel `texel`; then its depth there and the barycentric weights of its second and third
// vertices.
bool shadow_covers(vec3 e0, vec3 e1, vec3 e2, vec3 d, uvec2 texel, out float depth, out vec2 bary) {
    precise vec2 p = vec2(texel) + 0.5;
    precise float w0 = e0.x * p.x + e0.y * p.y + e0.z;
    precise float w1 = e1.x * p.x + e1.y * p.y + e1.z;
    precise float w2 = e2.x * p.x + e2.y * p.y + e2.z;
    if (!(shadow_edge_inside(e0, w0) && shadow_edge_inside(e1, w1) && shadow_edge_inside(e2, w2))) {
        return false;
    }
    float sum = w0 + w1 + w2;
    depth = max((w0 * d.x + w1 * d.y + w2 * d.z) / sum, 0.0);
    bary = vec2(w1, w2) / sum;
    return true;
}

// Whether the triangle with oriented edges e0..e2 and vertex depths d covers every texel centre
// of the texels lo..hi (inclusive), and then `far`, a depth no covered centre among them exceeds
// as shadow_covers computes it. Each corner centre must be inside every edge by a margin of
// 1e-5 of the terms' magnitude (far beyond the evaluation's rounding): an edge function is
// affine, so every centre between the corners is inside too. A triangle's depth along any line
// of texel space is a ratio of two affine functions (affine under an orthographic light), so
// over the box it is largest at a corner; `far` adds 1e-5 of the largest vertex depth for
// rounding.
bool shadow_covers_box(vec3 e0, vec3 e1, vec3 e2, vec3 d, uvec2 lo, uvec2 hi, out float far) {
    far = 0.0;
    for (uint k = 0u; k < 4u; ++k) {
        vec2 p = vec2(uvec2((k & 1u) == 0u ? lo.x : hi.x, (k & 2u) == 0u ? lo.y : hi.y)) + 0.5;
        vec3 w = vec3(dot(e0, vec3(p, 1.0)), dot(e1, vec3(p, 1.0)), dot(e2, vec3(p, 1.0)));
        vec3 scale = vec3(dot(abs(e0), vec3(p, 1.0)), dot(abs(e1), vec3(p, 1.0)), dot(abs(e2), vec3(p, 1.0)));
        if (!all(greaterThan(w, 1e-5 * scale))) {
            return false;
        }
        far = max(far, dot(w, d) / (w.x + w.y + w.z));
    }
    far += 1e-5 * max(abs(d.x), max(abs(d.y), abs(d.z)));
    return true;
}

// Whether triangle `tri` is opaque at barycentrics `bary` of texel `texel`: cut out as the
// traversal cuts (the same test), a blend's coverage hashed per texel and layer.
bool shadow_opaque(uint tri, vec2 bary, uvec2 texel) {
    if (HAS_ALPHA && floatBitsToUint(bvh_tri_v(tri, 1u).w) != 0u) {
        return bvh_alpha_opaque(tri, bary, vec3(vec2(texel) + 0.5, float(params.offset)), vec3(0.0));
    }
    return true;
}

#endif
