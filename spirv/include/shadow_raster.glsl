// The shadow rasterizer's shared part (shadow_bin.comp, shadow_raster.comp): a triangle's
// vertices in a layer's homogeneous texel space and the tiles its box can touch.
//
// Vertices are transformed by the layer's rows into (X, Y, D, W) = (x w, y w, depth, w), x and y
// in texels. Rasterization is homogeneous (Olano and Greer 1997): a texel centre (px, py) is
// covered when (px, py, 1) is a positive combination of the three (X, Y, W), so no clipping is
// needed for vertices behind a perspective light (w ≤ 0): those triangles bin into every tile of
// the planes they do not lie wholly outside.
#ifndef UMBRA_SHADOW_RASTER_GLSL
#define UMBRA_SHADOW_RASTER_GLSL

// Vertex k of BVH triangle `tri` in the layer's homogeneous texel space.
vec4 shadow_vertex(uint tri, uint k) {
    vec4 p = vec4(bvh_tri_v(tri, k).xyz, 1.0);
    return vec4(dot(params.row0, p), dot(params.row1, p), dot(params.row2, p), dot(params.row3, p));
}

// The inclusive tile range (x0, y0, x1, y1) a triangle can cover; false when it covers none.
bool shadow_tile_range(vec4 v0, vec4 v1, vec4 v2, out uvec4 range) {
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
    uint last = params.tiles - 1u;
    range = uvec4(0u, 0u, last, last);
    if (!any(out_w)) {
        // All in front: the projected box, widened by a texel against rounding.
        vec2 a = v0.xy / v0.w;
        vec2 b = v1.xy / v1.w;
        vec2 c = v2.xy / v2.w;
        vec2 lo = clamp(floor(min(a, min(b, c))) - 1.0, vec2(0.0), vec2(s - 1.0));
        vec2 hi = clamp(ceil(max(a, max(b, c))) + 1.0, vec2(0.0), vec2(s - 1.0));
        range = uvec4(uvec2(lo) / SHADOW_TILE, uvec2(hi) / SHADOW_TILE);
    }
    return true;
}

#endif
