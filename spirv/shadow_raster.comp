#version 460
// Shadow maps, rasterization: one workgroup per tile of SHADOW_TILE² texels, one invocation per
// texel. The workgroup sets up the tile's triangles (from shadow_bin.comp's list) 256 at a time
// in shared memory; each invocation tests its texel centre against them and keeps the nearest
// linear depth, so every texel is written once, by its owner, without atomics, and the result
// does not depend on the lists' order.
//
// Coverage is homogeneous (shadow_raster.glsl): the edge function of edge (a, b) is
// cross(a, b) · (px, py, 1) over (X, Y, W). A shared edge gives its two triangles exactly
// negated coefficients (the cross product of the same two vectors in the other order, the same
// vertices transformed by the same operations), and once each triangle is oriented by its
// determinant's sign the two evaluate exactly negated values: a texel centre is inside one of
// them or on the edge of both, where the tie rule (coefficient a > 0, or a = 0 and b > 0) gives
// it to exactly one. No cracks, no double hits, whatever the winding. Depth is the linear depth
// interpolated with the homogeneous barycentrics, clamped at 0 (casters between the light and
// the near plane still cast: "pancaking").
#extension GL_GOOGLE_include_directive : require
#include "kernel/shadow_raster.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

const bool BECKMANN = false;
#include "shading.glsl"
#include "shadow_raster.glsl"

const uint NO_TRIANGLE = 0xffffffffu;
const uint BATCH = 256u;

shared vec3 edge0[BATCH];
shared vec3 edge1[BATCH];
shared vec3 edge2[BATCH];
shared vec3 depths[BATCH];
shared uint tris[BATCH];

// Whether an oriented edge function's zero counts as inside (the tie rule).
bool edge_owns(vec3 e) {
    return e.x > 0.0 || (e.x == 0.0 && e.y > 0.0);
}

bool edge_inside(vec3 e, float value) {
    return value > 0.0 || (value == 0.0 && edge_owns(e));
}

void setup(uint slot, uint tri) {
    tris[slot] = NO_TRIANGLE;
    if (tri == NO_TRIANGLE) {
        return;
    }
    vec4 a = shadow_vertex(tri, 0u);
    vec4 b = shadow_vertex(tri, 1u);
    vec4 c = shadow_vertex(tri, 2u);
    precise vec3 e0 = cross(b.xyw, c.xyw);
    precise vec3 e1 = cross(c.xyw, a.xyw);
    precise vec3 e2 = cross(a.xyw, b.xyw);
    precise float det = dot(a.xyw, e0);
    if (det == 0.0 || isnan(det) || isinf(det)) {
        return;  // edge-on to the light: covers no texel centre
    }
    float sign_ = det > 0.0 ? 1.0 : -1.0;
    edge0[slot] = e0 * sign_;
    edge1[slot] = e1 * sign_;
    edge2[slot] = e2 * sign_;
    depths[slot] = vec3(a.z, b.z, c.z);
    tris[slot] = tri;
}

void main() {
    uvec2 tile = gl_WorkGroupID.xy;
    uvec2 texel = tile * SHADOW_TILE + gl_LocalInvocationID.xy;
    bool mine = all(lessThan(texel, uvec2(params.size)));
    uint t = tile.y * params.tiles + tile.x;
    uint start = min(tile_start[t], params.capacity);
    uint count = min(tile_count[t], params.capacity - start);
    // Every invocation has its count: zero it for the next layer's counting pass.
    barrier();
    if (gl_LocalInvocationIndex == 0u) {
        tile_count[t] = 0u;
    }
    precise vec3 centre = vec3(vec2(texel) + 0.5, 1.0);
    float nearest = BVH_INF;
    for (uint base = 0u; base < count; base += BATCH) {
        uint i = base + gl_LocalInvocationIndex;
        barrier();
        setup(gl_LocalInvocationIndex, i < count ? tile_tris[start + i] : NO_TRIANGLE);
        barrier();
        uint n = min(BATCH, count - base);
        for (uint j = 0u; j < n; ++j) {
            uint tri = tris[j];
            if (tri == NO_TRIANGLE) {
                continue;
            }
            vec3 e0 = edge0[j];
            vec3 e1 = edge1[j];
            vec3 e2 = edge2[j];
            precise float w0 = e0.x * centre.x + e0.y * centre.y + e0.z;
            precise float w1 = e1.x * centre.x + e1.y * centre.y + e1.z;
            precise float w2 = e2.x * centre.x + e2.y * centre.y + e2.z;
            if (!(edge_inside(e0, w0) && edge_inside(e1, w1) && edge_inside(e2, w2))) {
                continue;
            }
            float sum = w0 + w1 + w2;
            vec3 d = depths[j];
            float depth = max((w0 * d.x + w1 * d.y + w2 * d.z) / sum, 0.0);
            if (depth < nearest && HAS_ALPHA && floatBitsToUint(bvh_tri_v(tri, 1u).w) != 0u) {
                // Cut out as the traversal cuts: the same test at the same barycentrics, a blend's
                // coverage hashed per texel and layer.
                vec3 origin = vec3(centre.xy, float(params.offset));
                if (!bvh_alpha_opaque(tri, vec2(w1, w2) / sum, origin, vec3(0.0))) {
                    continue;
                }
            }
            nearest = min(nearest, depth);
        }
    }
    if (mine) {
        imageStore(shadow_depth, int(params.offset + texel.y * params.size + texel.x), vec4(nearest));
    }
}
