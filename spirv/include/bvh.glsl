// BVH traversal: closest hit and any hit, a watertight ray/triangle test (Woop, Benthin and Wald
// 2013) and a robust slab test (Ize 2013) on quantized boxes. The ray set-up and triangle test
// are those of src/bvh/traverse.rs operation for operation (keep them in step); the walk reads
// the 4-wide GPU layout (`GpuBvhNode` in src/bvh/gpu.rs), whose 8-bit boxes contain the binary
// BVH's and whose slab test is widened by a bound on its rounding, so it culls no box an exact
// test would keep; both keep the same tie rule, so both find the same nearest hit (up to a GPU's
// rounding of divisions).
//
// The including kernel declares, before including this file, the BVH as two read-only storage
// texel buffers of RGBA32UI (`GpuBvhNode`s as four texels each, `BvhTri`s as three):
//   layout(rgba32ui) uniform readonly uimageBuffer bvh_node_texels;
//   layout(rgba32ui) uniform readonly uimageBuffer bvh_tri_texels;
// Texel buffers rather than storage buffers: on llvmpipe (Mesa 22) a storage-buffer load is a loop
// over the SIMD lanes with a bounds check and a branch per component, a texel read a branch-free
// gather (docs/history/2026-11-30.md, first round: +25-40 % rays/s); and imageLoad rather than
// texelFetch, which llvmpipe calls as a function (spilling every live vector register around each
// call) where it inlines imageLoad (+5-10 %). GPUs read all of them through their caches. Every
// arithmetic result the watertight test depends on is `precise`, so the compiler cannot contract
// a*b - c*d into an fma on one side of a shared edge and not on the other.
#ifndef UMBRA_BVH_GLSL
#define UMBRA_BVH_GLSL

#define BVH_MAX_DEPTH 64u
// Run at the start of every walk-loop iteration: a kernel that counts them (pathtrace.comp)
// defines it before including this file.
#ifndef BVH_ITERATION
#define BVH_ITERATION
#endif
const float BVH_DIR_EPS = 1e-20;
const float BVH_SLAB_ROBUST = 1.0 + 1.0 / 1048576.0;
const float BVH_INF = uintBitsToFloat(0x7f800000u);

// GPU node n's four texels (GpuBvhNode in src/bvh/gpu.rs): 0 the grid's origin and step.x,
// 1 step.y, step.z and the lower planes x, y, 2 lower z and upper x, y, z (one byte per child in
// each plane word), 3 the child words: index << 4 | count, count 0 an inner node, BVH_NO_CHILD
// absent, else a leaf's triangle count.
uvec4 bvh_node(uint n, uint k) { return imageLoad(bvh_node_texels, int(4u * n + k)); }
const uint BVH_NO_CHILD = 15u;
// Vertex k of triangle i (BVH order); w: v0's original index, v1's alpha-mode bits.
vec4 bvh_tri_v(uint i, uint k) { return uintBitsToFloat(imageLoad(bvh_tri_texels, int(3u * i + k))); }

struct Hit {
    float t;
    uint tri;   // index in BVH order
    vec2 bary;  // weights of the second and third vertices; an implicit shape's octahedral normal
};

// Whether BVH slot `tri` is an implicit shape's procedural primitive (v2.w: its program's first
// texel, 0 for a triangle); always false in kernels not specialised for implicit shapes.
bool bvh_is_implicit(uint tri) {
    if (HAS_IMPLICIT) {
        return floatBitsToUint(bvh_tri_v(tri, 2u).w) != 0u;
    }
    return false;
}

struct BvhRay {
    vec3 origin;
    vec3 inv_dir;
    vec3 shear;
    uint kx;
    uint ky;
    uint kz;
};

BvhRay bvh_ray(vec3 origin, vec3 dir) {
    BvhRay r;
    vec3 a = abs(dir);
    r.kz = a.x > a.y ? (a.x > a.z ? 0u : 2u) : (a.y > a.z ? 1u : 2u);
    r.kx = (r.kz + 1u) % 3u;
    r.ky = (r.kx + 1u) % 3u;
    if (dir[r.kz] < 0.0) {
        uint k = r.kx;
        r.kx = r.ky;
        r.ky = k;
    }
    precise vec3 shear = vec3(dir[r.kx] / dir[r.kz], dir[r.ky] / dir[r.kz], 1.0 / dir[r.kz]);
    r.shear = shear;
    // Tiny components become eps with their sign bit (Rust: copysign), so 0 * inf never occurs.
    uvec3 sign_bits = floatBitsToUint(dir) & 0x80000000u;
    vec3 eps = uintBitsToFloat(floatBitsToUint(BVH_DIR_EPS) | sign_bits);
    vec3 nudged = mix(dir, eps, lessThan(a, vec3(BVH_DIR_EPS)));
    r.inv_dir = 1.0 / nudged;
    r.origin = origin;
    return r;
}

// Offsets a ray origin off the surface along n by a few ulps (Wächter and Binder, Ray Tracing
// Gems ch. 6), so the new ray neither re-hits its own triangle nor tunnels through a neighbour.
vec3 offset_ray(vec3 p, vec3 n) {
    ivec3 of_i = ivec3(256.0 * n);
    vec3 p_i = intBitsToFloat(floatBitsToInt(p) + mix(of_i, -of_i, lessThan(p, vec3(0.0))));
    return mix(p_i, p + (1.0 / 65536.0) * n, lessThan(abs(p), vec3(1.0 / 32.0)));
}

// The next float above x (Rust's f32::next_up for finite x).
float bvh_next_up(float x) {
    uint bits = floatBitsToUint(x);
    return x > 0.0 ? uintBitsToFloat(bits + 1u) : (x == 0.0 ? uintBitsToFloat(1u) : uintBitsToFloat(bits - 1u));
}

// The watertight test's terms for triangle i (Woop et al. 2013): the edge functions u, v, w of
// the ray's sheared frame (all of one sign where the ray meets the triangle), the scaled
// distance big_t (t = big_t / (u + v + w)), the triangle's index in the input (`order`) and its
// alpha-mode bits (`alpha`).
void bvh_edge_functions(BvhRay r, uint i, out float u, out float v, out float w, out float big_t, out uint order,
                        out uint alpha) {
    vec4 v0 = bvh_tri_v(i, 0u);
    vec4 v1 = bvh_tri_v(i, 1u);
    order = floatBitsToUint(v0.w);
    alpha = floatBitsToUint(v1.w);
    precise vec3 a = v0.xyz - r.origin;
    precise vec3 b = v1.xyz - r.origin;
    precise vec3 c = bvh_tri_v(i, 2u).xyz - r.origin;
    precise float ax = a[r.kx] - r.shear.x * a[r.kz];
    precise float ay = a[r.ky] - r.shear.y * a[r.kz];
    precise float bx = b[r.kx] - r.shear.x * b[r.kz];
    precise float by = b[r.ky] - r.shear.y * b[r.kz];
    precise float cx = c[r.kx] - r.shear.x * c[r.kz];
    precise float cy = c[r.ky] - r.shear.y * c[r.kz];
    precise float pu = cx * by - cy * bx;
    precise float pv = ax * cy - ay * cx;
    precise float pw = bx * ay - by * ax;
    precise float pt = pu * (r.shear.z * a[r.kz]) + pv * (r.shear.z * b[r.kz]) + pw * (r.shear.z * c[r.kz]);
    u = pu;
    v = pv;
    w = pw;
    big_t = pt;
}

// Watertight test against triangle i: true with t in (tmin, tmax), the barycentrics, the
// triangle's index in the input (`order`, which breaks ties between equally near hits) and its
// alpha-mode bits (`alpha`: 0 opaque, 1 mask, 2 blend).
bool bvh_intersect(BvhRay r, uint i, float tmin, float tmax, out float t, out vec2 bary, out uint order,
                   out uint alpha) {
    precise float u;
    precise float v;
    precise float w;
    precise float big_t;
    bvh_edge_functions(r, i, u, v, w, big_t, order, alpha);
    t = 0.0;
    bary = vec2(0.0);
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) {
        return false;
    }
    precise float det = u + v + w;
    if (det == 0.0) {
        return false;
    }
    precise float tt = big_t / det;
    if (!(tt > tmin && tt < tmax)) {
        return false;
    }
    t = tt;
    bary = vec2(v / det, w / det);
    return true;
}

// min and max as selects: GLSL's min and max must return the other operand for a NaN, which
// llvmpipe builds from three instructions (minps, an unordered compare, a blend) where a select
// is the one instruction x86's minps is. The slab test never sees a NaN (bvh_ray nudges tiny
// direction components, boxes are finite), so both give the same values.
float bvh_min(float a, float b) { return a < b ? a : b; }
float bvh_max(float a, float b) { return a > b ? a : b; }

// A node's grid in ray units, per axis: a plane q grid steps from the origin is at distance
// q * a + b, with a = step * inv_dir and b = (origin - o) * inv_dir. Computed so, a distance is
// off by at most about 2^-24 * (765 |a| + 3 |b|) (a and b rounded once and twice, the product and
// sum once each, inv_dir once); `slack` is over five times that, subtracted from entries
// (b_near) and added to exits (b_far), so the computed interval holds the exact one. A ray nearly
// parallel to an axis has a huge |a| and |b| there, and so a huge slack: that axis then never cuts
// the interval short, as a wrongly signed distance could (both stay finite: steps are at most
// 2^52 and ray origins within about 3e18 of the scene, GpuBvhNode). The near planes of an axis
// are the lower ones for a positive direction, the upper ones for a negative (`near`, `far`: the
// plane words to read).
struct BvhGrid {
    vec3 a;
    vec3 b_near;
    vec3 b_far;
    uvec3 near;
    uvec3 far;
};

BvhGrid bvh_grid(BvhRay r, uvec4 t0, uvec4 t1, uvec4 t2) {
    BvhGrid g;
    g.a = uintBitsToFloat(uvec3(t0.w, t1.xy)) * r.inv_dir;
    vec3 b = (uintBitsToFloat(t0.xyz) - r.origin) * r.inv_dir;
    vec3 slack = (256.0 * abs(g.a) + 2.0 * abs(b)) * (1.0 / 1048576.0);
    g.b_near = b - slack;
    g.b_far = b + slack;
    bvec3 positive = greaterThanEqual(r.inv_dir, vec3(0.0));
    uvec3 lo = uvec3(t1.zw, t2.x);
    uvec3 hi = t2.yzw;
    g.near = mix(hi, lo, positive);
    g.far = mix(lo, hi, positive);
    return g;
}

// Entry distance of the ray into child c's box (bytes c of the plane words) within [tmin, tmax],
// or BVH_INF; always BVH_INF for an absent child.
float bvh_slab(BvhGrid g, uint c, uint count, float tmin, float tmax) {
    vec3 near3 = vec3((g.near >> (8u * c)) & 255u) * g.a + g.b_near;
    vec3 far3 = vec3((g.far >> (8u * c)) & 255u) * g.a + g.b_far;
    float near = bvh_max(bvh_max(near3.x, near3.y), bvh_max(near3.z, tmin));
    // tmax is scaled: a box whose entry is just past the nearest hit so far as the triangle test
    // rounded it (a hit on its face, as on every axis-aligned wall) is still visited, for the tie
    // rule of bvh_trace.
    float far = bvh_min(bvh_min(bvh_min(far3.x, far3.y), far3.z), tmax * BVH_SLAB_ROBUST);
    return near <= far && count != BVH_NO_CHILD ? near : BVH_INF;
}

#include "implicit.glsl"

#ifdef UMBRA_ALPHA_TEST
// Whether a hit at barycentrics `bary` of triangle `tri` (in BVH order), whose material is
// alpha-masked or blended (bvh_tri_v(tri, 1u).w's bits: 1 mask, 2 blend), is opaque for a ray from
// `origin` along `dir`. Defined by shading.glsl; only kernels that shade the scene define UMBRA_ALPHA_TEST
// (and the specialization constant HAS_ALPHA), the others see every triangle as opaque.
bool bvh_alpha_opaque(uint tri, vec2 bary, vec3 origin, vec3 dir);
#endif

// Orders two (distance, node) pairs by distance: one comparator of a sorting network.
#define BVH_SORT2(da, na, db, nb)      \
    {                                  \
        bool swap_ = db < da;          \
        float d_ = da;                 \
        uint n_ = na;                  \
        da = swap_ ? db : da;          \
        na = swap_ ? nb : na;          \
        db = swap_ ? d_ : db;          \
        nb = swap_ ? n_ : nb;          \
    }

// One node visited: its leaf children hit, as triangle ranges (`first` and running `end`, so
// triangle k of the visit is in the first child whose end exceeds k), and its inner children hit
// (within the nearest hit so far), sorted nearest first: the nearest to descend into, the others
// as one stack entry (bits 31..8 the node's first inner child, 7..6 how many remain, 1 to 3, then
// their offsets from it, two bits each, the next one highest; a node's inner children have
// consecutive GPU indices, GpuBvhNode::from_bvh).
struct BvhVisit {
    uvec4 first;
    uvec4 end;
    uint inner;
    uint nearest;
    uint entry;
};

BvhVisit bvh_visit(BvhRay r, uint node, float tmin, float tmax) {
    BvhGrid g = bvh_grid(r, bvh_node(node, 0u), bvh_node(node, 1u), bvh_node(node, 2u));
    uvec4 words = bvh_node(node, 3u);
    uvec4 count = words & 15u;
    uvec4 index = words >> 4u;
    float d0 = bvh_slab(g, 0u, count.x, tmin, tmax);
    float d1 = bvh_slab(g, 1u, count.y, tmin, tmax);
    float d2 = bvh_slab(g, 2u, count.z, tmin, tmax);
    float d3 = bvh_slab(g, 3u, count.w, tmin, tmax);
    BvhVisit v;
    v.first = index;
    v.end.x = d0 != BVH_INF ? count.x : 0u;
    v.end.y = v.end.x + (d1 != BVH_INF ? count.y : 0u);
    v.end.z = v.end.y + (d2 != BVH_INF ? count.z : 0u);
    v.end.w = v.end.z + (d3 != BVH_INF ? count.w : 0u);
    // Inner children hit (bvh_slab's entry is within the nearest hit so far): their distances,
    // BVH_INF for the others.
    float k0 = count.x == 0u ? d0 : BVH_INF;
    float k1 = count.y == 0u ? d1 : BVH_INF;
    float k2 = count.z == 0u ? d2 : BVH_INF;
    float k3 = count.w == 0u ? d3 : BVH_INF;
    uint n0 = index.x;
    uint n1 = index.y;
    uint n2 = index.z;
    uint n3 = index.w;
    uint first = min(min(count.x == 0u ? n0 : 0xffffffffu, count.y == 0u ? n1 : 0xffffffffu),
                     min(count.z == 0u ? n2 : 0xffffffffu, count.w == 0u ? n3 : 0xffffffffu));
    BVH_SORT2(k0, n0, k1, n1);
    BVH_SORT2(k2, n2, k3, n3);
    BVH_SORT2(k0, n0, k2, n2);
    BVH_SORT2(k1, n1, k3, n3);
    BVH_SORT2(k1, n1, k2, n2);
    v.inner = uint(k0 != BVH_INF) + uint(k1 != BVH_INF) + uint(k2 != BVH_INF) + uint(k3 != BVH_INF);
    v.nearest = n0;
    v.entry = (first << 8u) | ((v.inner - 1u) << 6u) | (((n1 - first) & 3u) << 4u) |
              (((n2 - first) & 3u) << 2u) | ((n3 - first) & 3u);
    return v;
}

// After visit `v`, moves `node` into its nearest inner child (the others pushed as one entry), or
// else to the next child of the entry on top of the stack (written back with the rest, or
// popped); `more` is false when the walk is over. The stack is the including walk's
// (bvh_walk.glsl): BVH_STACK_TOP is its top entry (anything when it is empty), and
// BVH_STACK_UPDATE(descend, push, pop, entry, rest) pushes `entry` if `push`, pops if `pop`, and
// otherwise, when the walk ascends (not `descend`) from a stack of one or more entries, writes
// `rest` over the top one.
#define BVH_ADVANCE(v, more)                                                                     \
    {                                                                                            \
        uint top_ = BVH_STACK_TOP;                                                               \
        uint rest_ = (top_ & 0xffffff00u) | ((((top_ >> 6u) & 3u) - 1u) << 6u) | ((top_ & 15u) << 2u); \
        bool descend_ = v.inner > 0u;                                                            \
        bool push_ = v.inner > 1u;                                                               \
        bool pop_ = !descend_ && sp > 0u && ((top_ >> 6u) & 3u) == 1u;                           \
        BVH_STACK_UPDATE(descend_, push_, pop_, v.entry, rest_);                                 \
        more = descend_ || sp > 0u;                                                              \
        if (descend_) {                                                                          \
            node = v.nearest;                                                                    \
            sp += push_ ? 1u : 0u;                                                               \
        } else if (sp > 0u) {                                                                    \
            node = (top_ >> 8u) + ((top_ >> 4u) & 3u);                                           \
            sp -= pop_ ? 1u : 0u;                                                                \
        }                                                                                        \
    }

// Whether register k of the stack is one the walk uses (k < BVH_STACK). A function of k, not the
// comparison written out: on two constants that would be an OpSpecConstantOp, which naga's SPIR-V
// reader rejects; the driver folds the call once the constant is set.
bool bvh_register(uint k) { return k < BVH_STACK; }

// The walk over a stack of BVH_STACK entries in registers, for a BVH whose walk never holds more
// (the scene feature `shallow_bvh`: GpuBvhNode::stack_depth at most BVH_REGISTERS; BVH_STACK, a
// specialization constant, is that depth), and over BVH_MAX_DEPTH entries in memory for any other.
// On llvmpipe a dynamically indexed array is a loop over the SIMD lanes per access, 12-19 % of the
// path tracer's time (docs/history/2026-12-04.md, fifth session: the registers took 0.66-1.00 times
// its time); a GPU keeps either in registers or its local memory. The registers are a shift
// register, s0_ the top: a push moves every entry one down, a pop one up (a select per register
// each), so no access is indexed. Registers at or past BVH_STACK are never written: the driver
// folds their selects away once the constant is set, so a push or pop costs what the BVH's depth
// needs (a Cornell box's walk holds one entry; 16 registers cost it 6 %,
// docs/history/2026-12-05.md, seventh session).
#define BVH_WALK bvh_walk_registers
#define BVH_STACK_DECL \
    uint s0_ = 0u, s1_ = 0u, s2_ = 0u, s3_ = 0u, s4_ = 0u, s5_ = 0u, s6_ = 0u, s7_ = 0u, s8_ = 0u, s9_ = 0u, s10_ = 0u, s11_ = 0u, s12_ = 0u, s13_ = 0u, s14_ = 0u, s15_ = 0u;
#define BVH_STACK_TOP s0_
#define BVH_STACK_UPDATE(descend, push, pop, entry, rest)                          \
    {                                                                              \
        s0_ = bvh_register(1u) && (pop) ? s1_ : s0_;                               \
        s1_ = bvh_register(2u) && (pop) ? s2_ : s1_;                               \
        s2_ = bvh_register(3u) && (pop) ? s3_ : s2_;                               \
        s3_ = bvh_register(4u) && (pop) ? s4_ : s3_;                               \
        s4_ = bvh_register(5u) && (pop) ? s5_ : s4_;                               \
        s5_ = bvh_register(6u) && (pop) ? s6_ : s5_;                               \
        s6_ = bvh_register(7u) && (pop) ? s7_ : s6_;                               \
        s7_ = bvh_register(8u) && (pop) ? s8_ : s7_;                               \
        s8_ = bvh_register(9u) && (pop) ? s9_ : s8_;                               \
        s9_ = bvh_register(10u) && (pop) ? s10_ : s9_;                             \
        s10_ = bvh_register(11u) && (pop) ? s11_ : s10_;                           \
        s11_ = bvh_register(12u) && (pop) ? s12_ : s11_;                           \
        s12_ = bvh_register(13u) && (pop) ? s13_ : s12_;                           \
        s13_ = bvh_register(14u) && (pop) ? s14_ : s13_;                           \
        s14_ = bvh_register(15u) && (pop) ? s15_ : s14_;                           \
        s15_ = bvh_register(15u) && (push) ? s14_ : s15_;                          \
        s14_ = bvh_register(14u) && (push) ? s13_ : s14_;                          \
        s13_ = bvh_register(13u) && (push) ? s12_ : s13_;                          \
        s12_ = bvh_register(12u) && (push) ? s11_ : s12_;                          \
        s11_ = bvh_register(11u) && (push) ? s10_ : s11_;                          \
        s10_ = bvh_register(10u) && (push) ? s9_ : s10_;                           \
        s9_ = bvh_register(9u) && (push) ? s8_ : s9_;                              \
        s8_ = bvh_register(8u) && (push) ? s7_ : s8_;                              \
        s7_ = bvh_register(7u) && (push) ? s6_ : s7_;                              \
        s6_ = bvh_register(6u) && (push) ? s5_ : s6_;                              \
        s5_ = bvh_register(5u) && (push) ? s4_ : s5_;                              \
        s4_ = bvh_register(4u) && (push) ? s3_ : s4_;                              \
        s3_ = bvh_register(3u) && (push) ? s2_ : s3_;                              \
        s2_ = bvh_register(2u) && (push) ? s1_ : s2_;                              \
        s1_ = bvh_register(1u) && (push) ? s0_ : s1_;                              \
        s0_ = (push) ? (entry) : (!(descend) && sp > 0u && !(pop) ? (rest) : s0_); \
    }
#include "bvh_walk.glsl"
#undef BVH_WALK
#undef BVH_STACK_DECL
#undef BVH_STACK_TOP
#undef BVH_STACK_UPDATE

// In memory, one stack word is stored, at a slot chosen per lane, by every lane (on SIMD CPUs,
// llvmpipe, a store under a divergent condition, and each extra store, costs a per-lane branch
// that mispredicts): the pushed entry, or the rest over the top one (a popped one's slot is
// free). A descent into a lone inner child writes the free slot above the top.
#define BVH_WALK bvh_walk_memory
#define BVH_STACK_DECL uint stack_[BVH_MAX_DEPTH];
#define BVH_STACK_TOP stack_[max(sp, 1u) - 1u]
#define BVH_STACK_UPDATE(descend, push, pop, entry, rest) \
    stack_[min((descend) ? sp : sp - 1u, BVH_MAX_DEPTH - 1u)] = (descend) ? (entry) : (rest);
#include "bvh_walk.glsl"

bool bvh_walk(vec3 origin, vec3 dir, float tmin, float tmax, bool any_hit, out Hit hit) {
    if (HAS_SHALLOW_BVH) {
        return bvh_walk_registers(origin, dir, tmin, tmax, any_hit, hit);
    }
    return bvh_walk_memory(origin, dir, tmin, tmax, any_hit, hit);
}

// The walk, and where the scene has alpha-tested triangles (UMBRA_ALPHA_TEST and HAS_ALPHA), their
// alpha test: a walk that ends on a hit the test cuts out walks again from just behind it (tmin =
// its t), until it ends on a surface or finds none. The test (a material read, a texture's bilinear
// lookup) thus runs once per walk, not inside the walk's triangle loop: a SIMD CPU (llvmpipe) runs
// every `if` body for all lanes, so there it cost every triangle test the lookup
// (TransmissionTest's masks made it 3.5x slower; docs/history/2026-12-02.md, "alpha tests after the
// walk"). An any-hit walk stops at the first opaque triangle and otherwise keeps the nearest
// alpha-tested candidate, so no opaque occluder before that candidate is skipped. The same hit as
// one walk testing alpha per triangle, but for triangles exactly as near as a cut-out one, which
// the next walk (t > tmin strictly) skips.
bool bvh_trace(vec3 origin, vec3 dir, float tmin, float tmax, bool any_hit, out Hit hit) {
#ifdef UMBRA_ALPHA_TEST
    if (HAS_ALPHA) {
        while (true) {
            if (!bvh_walk(origin, dir, tmin, tmax, any_hit, hit)) {
                return false;
            }
            if (floatBitsToUint(bvh_tri_v(hit.tri, 1u).w) == 0u || bvh_alpha_opaque(hit.tri, hit.bary, origin, dir)) {
                return true;
            }
            tmin = hit.t;
        }
    }
#endif
    return bvh_walk(origin, dir, tmin, tmax, any_hit, hit);
}

// Nearest hit with t in (tmin, tmax).
bool bvh_closest(vec3 origin, vec3 dir, float tmin, float tmax, out Hit hit) {
    return bvh_trace(origin, dir, tmin, tmax, false, hit);
}

// Whether anything lies on the ray with t in (tmin, tmax).
bool bvh_any(vec3 origin, vec3 dir, float tmin, float tmax) {
    Hit hit;
    return bvh_trace(origin, dir, tmin, tmax, true, hit);
}

#endif
