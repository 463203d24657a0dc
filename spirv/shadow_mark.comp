#version 460
// Shadow maps, step 0 when the maps render for a view (src/passes/shadow.rs, ShadowView): the
// G-buffer's pixels mark, in the cascade of each directional light the lighting pass will read
// for them, the tiles within `reach` texels of where their points land (the filter's footprint,
// the normal offset and a texel to spare), so the rasterizer renders only tiles some pixel reads
// (Fernando et al. 2001's adaptive shadow maps, Haar 2015's virtual shadow maps: a view-driven
// subset of a large map). A point is the lighting pass's (restir.glsl's gbuffer_point), its
// cascade picked as shadow.glsl's shadow_pick_layer picks it; within a relative 1e-5 of a split
// both cascades are marked, as two kernels' arithmetic may round the view depth apart.
//
// One invocation marks a 2 × 2 block of pixels: a light's splits are read once per block and a
// cascade's rows once per block and cascade (on llvmpipe the texel fetches and the invocation
// cost more than the arithmetic; caching the cascades in shared memory behind barriers measured
// 4× slower). Every mark is the same plain store of 1, made only where the tile reads 0 (a store
// to a line other cores share would take it from them): the races between pixels are benign.
#extension GL_GOOGLE_include_directive : require
#include "kernel/shadow_mark.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

#include "camera.glsl"
#include "shadow_layers.glsl"

// The cascade among `count` covering view depth `depth`: the first whose split lies at or beyond
// it; false beyond the last.
bool cascade_of(float splits[SHADOW_MAX_CASCADES], uint count, float depth, out uint j) {
    j = 0u;
    while (j + 1u < count && splits[j] < depth) {
        ++j;
    }
    return !(splits[j] < depth);
}

// Marks the tiles of layer `layer` (rows r0, r1, r3, `size` texels a side) within `reach` texels
// of p.
void mark(uint layer, vec4 r0, vec4 r1, vec4 r3, uint size, vec3 p) {
    vec4 p1 = vec4(p, 1.0);
    float w = dot(r3, p1);
    vec2 uv = vec2(dot(r0, p1), dot(r1, p1)) / w;
    if (!(w > 0.0) || any(isnan(uv))) {
        return;
    }
    float edge = float(size) - 1.0;
    uvec2 t0 = uvec2(clamp(floor(uv - params.reach), vec2(0.0), vec2(edge))) / SHADOW_TILE;
    uvec2 t1 = uvec2(clamp(floor(uv + params.reach), vec2(0.0), vec2(edge))) / SHADOW_TILE;
    uint at = layer * params.tiles * params.tiles;
    for (uint y = t0.y; y <= t1.y; ++y) {
        for (uint x = t0.x; x <= t1.x; ++x) {
            uint i = at + y * params.tiles + x;
            if (tile_marks[i] == 0u) {
                tile_marks[i] = 1u;
            }
        }
    }
}

void main() {
    // The block's points and view depths (0: no point).
    vec3 points[4];
    float depths[4];
    bool any_point = false;
    for (uint q = 0u; q < 4u; ++q) {
        ivec2 pixel = ivec2(gl_GlobalInvocationID.xy * 2u + uvec2(q & 1u, q >> 1u));
        float depth = all(lessThan(uvec2(pixel), params.size)) ? imageLoad(gb_depth, pixel).x : 0.0;
        depths[q] = 0.0;
        if (depth > 0.0) {
            vec3 origin;
            vec3 dir;
            camera_ray(params.camera.origin, params.camera.forward, params.camera.right, params.camera.up,
                       params.camera.orthographic != 0u, vec2(pixel) + 0.5, params.size, origin, dir);
            points[q] = origin + dir * (depth / dot(dir, params.camera.forward));
            // (Positive: the point lies in front of the camera.)
            depths[q] = max(dot(points[q] - params.camera.origin, params.camera.forward), 1e-30);
            any_point = true;
        }
    }
    if (!any_point) {
        return;
    }
    for (uint k = 0u; k < params.lights; ++k) {
        uvec4 rec = imageLoad(shadow_texels, int(SHADOW_HEADER_TEXELS + k));
        if (rec.z != SHADOW_LIGHT_CASCADES) {
            continue;
        }
        uint count = min(rec.y, SHADOW_MAX_CASCADES);
        float splits[SHADOW_MAX_CASCADES];
        for (uint j = 0u; j < count; ++j) {
            splits[j] = shadow_header(rec.x + SHADOW_LAYER_TEXELS * j + 5u).z;
        }
        uint first = (rec.x - params.layers_at) / SHADOW_LAYER_TEXELS;
        // The last cascade read, its rows and size.
        uint held = SHADOW_MAX_CASCADES;
        vec4 r0;
        vec4 r1;
        vec4 r3;
        uint size;
        uint nearer = SHADOW_MAX_CASCADES;
        for (uint q = 0u; q < 8u; ++q) {
            // Each point twice: its view depth a little nearer (q even) and farther (q odd).
            float depth = depths[q >> 1u] * ((q & 1u) == 0u ? 1.0 - 1e-5 : 1.0 + 1e-5);
            uint j;
            if (depth == 0.0 || !cascade_of(splits, count, depth, j)) {
                nearer = SHADOW_MAX_CASCADES;
                continue;
            }
            // The farther depth in the nearer one's cascade: marked already.
            bool again = (q & 1u) == 1u && j == nearer;
            nearer = j;
            if (again) {
                continue;
            }
            if (j != held) {
                uint at = rec.x + SHADOW_LAYER_TEXELS * j;
                r0 = shadow_header(at);
                r1 = shadow_header(at + 1u);
                r3 = shadow_header(at + 3u);
                size = imageLoad(shadow_texels, int(at + 4u)).y;
                held = j;
            }
            mark(first + j, r0, r1, r3, size, points[q >> 1u]);
        }
    }
}
