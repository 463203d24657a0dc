// BVH traversal: closest hit and any hit, a watertight ray/triangle test (Woop, Benthin and Wald
// 2013) and a robust slab test (Ize 2013). src/bvh/traverse.rs is the same algorithm, operation
// for operation; keep them in step.
//
// The including kernel declares, before including this file:
//   readonly buffer ... { BvhNode bvh_nodes[]; };
//   readonly buffer ... { BvhTri bvh_tris[]; };
// Every arithmetic result the watertight test depends on is `precise`, so the compiler cannot
// contract a*b - c*d into an fma on one side of a shared edge and not on the other.
#ifndef UMBRA_BVH_GLSL
#define UMBRA_BVH_GLSL

#define BVH_MAX_DEPTH 64
const float BVH_DIR_EPS = 1e-20;
const float BVH_SLAB_ROBUST = 1.0 + 1.0 / 1048576.0;
const float BVH_INF = uintBitsToFloat(0x7f800000u);

struct Hit {
    float t;
    uint tri;   // index in BVH order
    vec2 bary;  // weights of the second and third vertices
};

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

// Watertight test against bvh_tris[i]: true with t in (tmin, tmax) and the barycentrics.
// Offsets a ray origin off the surface along n by a few ulps (Wächter and Binder, Ray Tracing
// Gems ch. 6), so the new ray neither re-hits its own triangle nor tunnels through a neighbour.
vec3 offset_ray(vec3 p, vec3 n) {
    ivec3 of_i = ivec3(256.0 * n);
    vec3 p_i = intBitsToFloat(floatBitsToInt(p) + mix(of_i, -of_i, lessThan(p, vec3(0.0))));
    return mix(p_i, p + (1.0 / 65536.0) * n, lessThan(abs(p), vec3(1.0 / 32.0)));
}

bool bvh_intersect(BvhRay r, uint i, float tmin, float tmax, out float t, out vec2 bary) {
    // Member by member: a whole-struct copy from a buffer is OpCopyLogical, which naga rejects.
    precise vec3 a = bvh_tris[i].v0.xyz - r.origin;
    precise vec3 b = bvh_tris[i].v1.xyz - r.origin;
    precise vec3 c = bvh_tris[i].v2.xyz - r.origin;
    precise float ax = a[r.kx] - r.shear.x * a[r.kz];
    precise float ay = a[r.ky] - r.shear.y * a[r.kz];
    precise float bx = b[r.kx] - r.shear.x * b[r.kz];
    precise float by = b[r.ky] - r.shear.y * b[r.kz];
    precise float cx = c[r.kx] - r.shear.x * c[r.kz];
    precise float cy = c[r.ky] - r.shear.y * c[r.kz];
    precise float u = cx * by - cy * bx;
    precise float v = ax * cy - ay * cx;
    precise float w = bx * ay - by * ax;
    t = 0.0;
    bary = vec2(0.0);
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) {
        return false;
    }
    precise float det = u + v + w;
    if (det == 0.0) {
        return false;
    }
    precise float big_t = u * (r.shear.z * a[r.kz]) + v * (r.shear.z * b[r.kz]) + w * (r.shear.z * c[r.kz]);
    precise float tt = big_t / det;
    if (!(tt > tmin && tt < tmax)) {
        return false;
    }
    t = tt;
    bary = vec2(v / det, w / det);
    return true;
}

// Entry distance of the ray into node n within [tmin, tmax], or BVH_INF.
float bvh_slab(BvhRay r, uint n, float tmin, float tmax) {
    vec3 t0 = (bvh_nodes[n].aabb_min - r.origin) * r.inv_dir;
    vec3 t1 = (bvh_nodes[n].aabb_max - r.origin) * r.inv_dir;
    vec3 lo = min(t0, t1);
    vec3 hi = max(t0, t1);
    float near = max(max(lo.x, lo.y), max(lo.z, tmin));
    float far = min(min(hi.x, hi.y), hi.z) * BVH_SLAB_ROBUST;
    far = min(far, tmax);
    return near <= far ? near : BVH_INF;
}

bool bvh_is_empty() {
    return bvh_nodes[0].tri_count == 0u && bvh_nodes[0].aabb_min.x > bvh_nodes[0].aabb_max.x;
}

// Front-to-back traversal with t in (tmin, tmax); any_hit stops at the first hit found.
#ifdef UMBRA_ALPHA_TEST
// Whether a hit at barycentrics `bary` of triangle `tri` (in BVH order), whose material is
// alpha-masked or blended (bvh_tris[tri].v1.w's bits: 1 mask, 2 blend), is opaque for a ray from
// `origin` along `dir`. Defined by shading.glsl; only kernels that shade the scene define UMBRA_ALPHA_TEST
// (and the specialization constant HAS_ALPHA), the others see every triangle as opaque.
bool bvh_alpha_opaque(uint tri, vec2 bary, vec3 origin, vec3 dir);
#endif

bool bvh_trace(vec3 origin, vec3 dir, float tmin, float tmax, bool any_hit, out Hit hit) {
    hit = Hit(tmax, 0xffffffffu, vec2(0.0));
    if (bvh_is_empty()) {
        return false;
    }
    BvhRay r = bvh_ray(origin, dir);
    uint stack[BVH_MAX_DEPTH];
    uint sp = 0u;
    uint node = 0u;
    bool found = false;
    while (true) {
        uint count = bvh_nodes[node].tri_count;
        uint first = bvh_nodes[node].left_first;
        if (count > 0u) {
            for (uint i = first; i < first + count; ++i) {
                float t;
                vec2 bary;
                if (bvh_intersect(r, i, tmin, tmax, t, bary)) {
#ifdef UMBRA_ALPHA_TEST
                    if (HAS_ALPHA && floatBitsToUint(bvh_tris[i].v1.w) != 0u && !bvh_alpha_opaque(i, bary, origin, dir)) {
                        continue;
                    }
#endif
                    found = true;
                    tmax = t;
                    hit = Hit(t, i, bary);
                    if (any_hit) {
                        return true;
                    }
                }
            }
            if (sp == 0u) {
                break;
            }
            node = stack[--sp];
            continue;
        }
        uint near = first;
        uint far = first + 1u;
        float d_near = bvh_slab(r, near, tmin, tmax);
        float d_far = bvh_slab(r, far, tmin, tmax);
        if (d_near > d_far) {
            uint k = near;
            near = far;
            far = k;
            float d = d_near;
            d_near = d_far;
            d_far = d;
        }
        if (d_near == BVH_INF) {
            if (sp == 0u) {
                break;
            }
            node = stack[--sp];
        } else {
            node = near;
            if (d_far != BVH_INF) {
                stack[sp++] = far;
            }
        }
    }
    return found;
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
