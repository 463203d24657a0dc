// Implicit shapes (UMBRA_implicit, src/scene/implicit.rs): signed distance programs, read from
// bvh_tri_texels after the triangles, and the sphere tracer the BVH walk runs inside a procedural
// primitive's box. Included by bvh.glsl; compiled in only where the kernel is specialised for
// implicit shapes (HAS_IMPLICIT).
//
// A shape's program (ImplicitShape::program), from its first texel: a header (instruction count,
// material, step scale, hit threshold as float bits), the world-to-node rows (3 texels), then
// IMPLICIT_INSTRUCTION_TEXELS texels per instruction in postfix order: a primitive (kind < 16)
// pushes its distance (kind and uniform scale; parameters; node-to-primitive rows), an operation
// (IMPLICIT_UNION, _INTERSECTION, _SUBTRACTION; its smoothness) pops two and pushes one.
//
// The march: sphere tracing with over-relaxation (Keinert et al. 2014, omega = IMPLICIT_RELAXATION;
// a step whose bounding sphere does not overlap the previous one is undone and the rest taken
// with omega = 1), at most IMPLICIT_MAX_STEPS distance evaluations per shape and ray, a hit where
// the distance falls below the shape's threshold (ImplicitShape::epsilon, 2e-5 of its box's
// diagonal), refined by two Newton steps along the ray; the normal is the distance's gradient
// (Quilez's tetrahedron of four evaluations). A march that runs out of steps inside the box is
// a miss, counted in implicit_marches_exhausted. No UVs: an implicit hit has none (textures read
// at UV 0).
#ifndef UMBRA_IMPLICIT_GLSL
#define UMBRA_IMPLICIT_GLSL

#include "octahedral.glsl"

// Marches of this invocation that ran out of steps (read by the kernel for its statistics).
uint implicit_marches_exhausted = 0u;

vec4 implicit_vec(uint k) { return uintBitsToFloat(imageLoad(bvh_tri_texels, int(k))); }
uvec4 implicit_uvec(uint k) { return imageLoad(bvh_tri_texels, int(k)); }

float implicit_box(vec3 p, vec3 b) {
    vec3 q = abs(p) - b;
    return length(max(q, vec3(0.0))) + min(max(q.x, max(q.y, q.z)), 0.0);
}

// Distance of primitive `kind` with parameters `a` at p (its own frame).
float implicit_primitive(uint kind, vec4 a, vec3 p) {
    if (kind == IMPLICIT_SPHERE) {
        return length(p) - a.x;
    } else if (kind == IMPLICIT_BOX) {
        return implicit_box(p, a.xyz);
    } else if (kind == IMPLICIT_ROUNDED_BOX) {
        return implicit_box(p, a.xyz) - a.w;
    } else if (kind == IMPLICIT_TORUS) {
        vec2 q = vec2(length(p.xz) - a.x, p.y);
        return length(q) - a.y;
    } else if (kind == IMPLICIT_CAPSULE) {
        vec3 q = vec3(p.x, p.y - clamp(p.y, -a.x, a.x), p.z);
        return length(q) - a.y;
    } else if (kind == IMPLICIT_CYLINDER) {
        vec2 d = abs(vec2(length(p.xz), p.y)) - vec2(a.y, a.x);
        return min(max(d.x, d.y), 0.0) + length(max(d, vec2(0.0)));
    }
    return dot(p, a.xyz) - a.w;  // IMPLICIT_PLANE
}

// Polynomial smooth minimum (Quilez): min lowered by at most k/4 where |a - b| < k.
float implicit_smin(float a, float b, float k) {
    float h = max(k - abs(a - b), 0.0) / max(k, 1e-30);
    return min(a, b) - h * h * k * 0.25;
}

// A lower bound of the world distance from p to the shape at `base` (negative inside).
float implicit_distance(uint base, vec3 p) {
    uvec4 head = implicit_uvec(base);
    vec4 w = vec4(p, 1.0);
    vec4 local = vec4(dot(implicit_vec(base + 1u), w), dot(implicit_vec(base + 2u), w),
                      dot(implicit_vec(base + 3u), w), 1.0);
    float stack[IMPLICIT_MAX_STACK];
    uint sp = 0u;
    for (uint i = 0u; i < head.x; ++i) {
        uint at = base + IMPLICIT_HEADER_TEXELS + IMPLICIT_INSTRUCTION_TEXELS * i;
        uvec4 instr = implicit_uvec(at);
        float k = uintBitsToFloat(instr.y);
        if (instr.x < IMPLICIT_UNION) {
            vec3 q = vec3(dot(implicit_vec(at + 2u), local), dot(implicit_vec(at + 3u), local),
                          dot(implicit_vec(at + 4u), local));
            stack[min(sp, IMPLICIT_MAX_STACK - 1u)] = k * implicit_primitive(instr.x, implicit_vec(at + 1u), q);
            sp += 1u;
        } else {
            float b = stack[max(sp, 1u) - 1u];
            float a = stack[max(sp, 2u) - 2u];
            // Intersection: max(a, b) = -min(-a, -b); subtraction: max(a, -b) = -min(-a, b).
            float sa = instr.x == IMPLICIT_UNION ? 1.0 : -1.0;
            float sb = instr.x == IMPLICIT_INTERSECTION ? -1.0 : 1.0;
            stack[max(sp, 2u) - 2u] = sa * implicit_smin(sa * a, sb * b, k);
            sp -= 1u;
        }
    }
    return uintBitsToFloat(head.z) * stack[0];
}

// The distance's gradient at p (unnormalised, in world units per unit): the tetrahedron of four
// evaluations h apart.
vec3 implicit_gradient(uint base, vec3 p, float h) {
    vec2 k = vec2(1.0, -1.0);
    vec3 g = k.xyy * implicit_distance(base, p + k.xyy * h) + k.yyx * implicit_distance(base, p + k.yyx * h)
        + k.yxy * implicit_distance(base, p + k.yxy * h) + k.xxx * implicit_distance(base, p + k.xxx * h);
    return g * (0.25 / h);
}

// Marches the shape at `base` along origin + t dir (dir need not be unit) for t in [t0, t1]
// (the box's span within the ray's interval). True on a hit, with t and the unit outward normal
// octahedrally encoded. The side the ray starts on is the sign of the distance there; a start on
// the surface (a ray leaving it) takes the side the ray moves into, and the march only hits once
// it has been a threshold away from the surface (`armed`), so a ray never hits its own start.
bool implicit_march(uint base, vec3 origin, vec3 dir, float t0, float t1, out float t_hit, out vec2 n_oct) {
    t_hit = 0.0;
    n_oct = vec2(0.0);
    float eps = uintBitsToFloat(implicit_uvec(base).w);
    float len = length(dir);
    float inv_len = 1.0 / len;
    float d0 = implicit_distance(base, origin + t0 * dir);
    float d1 = implicit_distance(base, origin + (t0 + eps * inv_len) * dir);
    float side = abs(d0) >= eps ? sign(d0) : (d1 >= d0 ? 1.0 : -1.0);
    bool armed = abs(d0) >= eps;
    float omega = IMPLICIT_RELAXATION;
    float t = t0;
    float t_prev = t0;
    float r_prev = 0.0;
    bool hit = false;
    bool left = false;
    for (uint i = 0u; i < IMPLICIT_MAX_STEPS; ++i) {
        float d = side * implicit_distance(base, origin + t * dir);
        // Over-relaxation failed: the spheres around this point and the previous one do not
        // overlap, so the surface may lie between them; back to the plain step.
        if (omega > 1.0 && r_prev > 0.0 && abs(d) + r_prev < (t - t_prev) * len) {
            t = t_prev + r_prev * inv_len;
            omega = 1.0;
            continue;
        }
        if (armed && d < eps) {
            hit = true;
            break;
        }
        armed = armed || d >= eps;
        float step = armed ? omega * d : max(d, eps);
        t_prev = t;
        r_prev = armed ? d : 0.0;
        t += step * inv_len;
        if (t > t1) {
            // Past the box: done, unless an over-relaxed step took it there (the surface may lie
            // beyond the plain step and before the exit): then the plain step, from omega = 1.
            if (omega > 1.0 && armed) {
                t = t_prev + r_prev * inv_len;
                omega = 1.0;
                continue;
            }
            left = true;
            break;
        }
    }
    if (!hit) {
        if (!left) {
            implicit_marches_exhausted += 1u;
        }
        return false;
    }
    vec3 g = implicit_gradient(base, origin + t * dir, eps);
    float g_len = length(g);
    // Two Newton steps onto the surface along the ray (the gradient kept), where the ray crosses
    // it at an angle (cosine over 0.01), the correction stays within 50 thresholds and the box: the hit
    // test alone leaves t short by up to the threshold over the cosine.
    float slope = dot(g, dir);
    for (uint k = 0u; k < 2u; ++k) {
        float dt = -implicit_distance(base, origin + t * dir) / slope;
        if (abs(slope) > 0.01 * g_len * len && abs(dt) * len < 50.0 * eps && t + dt >= t0 && t + dt <= t1) {
            t += dt;
        }
    }
    if (!(t >= t0 && t <= t1) || g_len == 0.0 || isnan(g_len)) {
        return false;
    }
    t_hit = t;
    n_oct = oct_encode(g / g_len);
    return true;
}

// The march of BVH slot `slot` (a procedural primitive: its box in v0.xyz, v1.xyz, its program
// at v2.w) for t in (tmin, tmax).
bool implicit_intersect(uint slot, uint program, vec3 origin, vec3 dir, vec3 inv_dir, float tmin, float tmax,
                        out float t, out vec2 n_oct) {
    vec3 lo = bvh_tri_v(slot, 0u).xyz;
    vec3 hi = bvh_tri_v(slot, 1u).xyz;
    vec3 a = (lo - origin) * inv_dir;
    vec3 b = (hi - origin) * inv_dir;
    vec3 near3 = min(a, b);
    vec3 far3 = max(a, b);
    float t0 = max(max(near3.x, near3.y), max(near3.z, tmin));
    float t1 = min(min(far3.x, far3.y), min(far3.z, tmax));
    t = 0.0;
    n_oct = vec2(0.0);
    if (!(t0 <= t1)) {
        return false;
    }
    return implicit_march(program, origin, dir, t0, t1, t, n_oct) && t > tmin && t < tmax;
}

#endif
