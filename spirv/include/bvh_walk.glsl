// The body of the BVH walk (bvh.glsl), included once per stack: BVH_WALK names the function,
// BVH_STACK_DECL declares its stack, BVH_STACK_TOP and BVH_STACK_UPDATE read and change it
// (BVH_ADVANCE). Front-to-back walk with t in (tmin, tmax); any_hit stops at the first hit found on
// an opaque triangle (alpha-tested ones are kept as the nearest candidate instead, see bvh_trace).
// The closest hit is the nearest, and of equally near ones (a ray through a shared edge) the one
// first in the input, so the answer does not depend on the order of the walk (the BVH's layout, its
// width, the CPU or the GPU): the brute-force reference keeps the lowest index too. Each iteration
// visits two nodes, then tests the triangles of the leaf children both hit. On a SIMD CPU
// (llvmpipe) every iteration runs the triangle loop's body at least once, whether or not any lane
// has a leaf (in Sponza most visits have none), so two visits per loop halve those empty runs:
// +20-30 % rays/s there (docs/history/2026-11-30.md, second round; three visits gained nothing
// more). The second visit's culling does not see the first's triangles yet, which costs a few extra
// visits and never a wrong answer. Everything per child is written out for constant child indices
// (registers, not memory).
bool BVH_WALK(vec3 origin, vec3 dir, float tmin, float tmax, bool any_hit, out Hit hit) {
    hit = Hit(tmax, 0xffffffffu, vec2(0.0));
    BvhRay r = bvh_ray(origin, dir);
    BVH_STACK_DECL
    uint sp = 0u;
    uint node = 0u;
    bool found = false;
    uint hit_order = 0xffffffffu;
    while (true) {
        BVH_ITERATION
        BvhVisit a = bvh_visit(r, node, tmin, tmax);
        bool more;
        BVH_ADVANCE(a, more);
        // When the walk ended with the first visit, the second (of the same node) is void.
        BvhVisit b = bvh_visit(r, node, tmin, tmax);
        if (more) {
            BVH_ADVANCE(b, more);
        } else {
            b.end = uvec4(0u);
        }
        uint from_b = a.end.w;
        for (uint k = 0u; k < from_b + b.end.w; ++k) {
            bool in_a = k < from_b;
            uint j = in_a ? k : k - from_b;
            uvec4 f = in_a ? a.first : b.first;
            uvec4 e = in_a ? a.end : b.end;
            uint i = j < e.x ? f.x + j : (j < e.y ? f.y + (j - e.x) : (j < e.z ? f.z + (j - e.y) : f.w + (j - e.z)));
            float t;
            vec2 bary;
            uint order;
            uint alpha;
            // After a hit, one equally near with a lower input index replaces it.
            float limit = found ? bvh_next_up(tmax) : tmax;
            bool hits = bvh_intersect(r, i, tmin, limit, t, bary, order, alpha);
            // A triangle transparent wherever it can be hit is never hit (alpha-tested scenes).
            if (HAS_ALPHA) {
                hits = hits && alpha != ALPHA_NEVER_HIT;
            }
            if (hits && (t < tmax || order < hit_order)) {
                found = true;
                tmax = t;
                hit_order = order;
                hit = Hit(t, i, bary);
                if (any_hit && alpha == 0u) {
                    return true;
                }
            }
            // A procedural primitive (an implicit shape's box; v2.w its program, 0 for a
            // triangle, whose test above never hits it): marched within the box. Compiled out of
            // kernels not specialised for implicit shapes (HAS_IMPLICIT).
            if (HAS_IMPLICIT) {
                uint program = floatBitsToUint(bvh_tri_v(i, 2u).w);
                float ts;
                vec2 n_oct;
                if (program != 0u && implicit_intersect(i, program, origin, dir, r.inv_dir, tmin, tmax, ts, n_oct)) {
                    found = true;
                    tmax = ts;
                    hit_order = floatBitsToUint(bvh_tri_v(i, 0u).w);
                    hit = Hit(ts, i, n_oct);
                    if (any_hit) {
                        return true;
                    }
                }
            }
        }
        if (!more) {
            break;
        }
    }
    return found;
}

