// Every struct shared with the host. Each has a #[repr(C)] twin in src/gpu/layout.rs with the
// same name and member names; tests/layout.rs compares their offsets and strides through naga.
// std430 rules apply: keep members in vec4-sized groups.
#ifndef UMBRA_LAYOUT_GLSL
#define UMBRA_LAYOUT_GLSL

// Push constants of test_pattern.comp.
struct PatternParams {
    uvec2 size;
    uint seed;
    uint frame;
};

// Push constants of test_buffer.comp.
struct BufferTestParams {
    uint count;
    uint add;
};

// One node of the flattened BVH (tinybvh's BVHNode, 32 bytes). Interior: tri_count == 0 and the
// children are left_first and left_first + 1. Leaf: tri_count triangles from left_first.
struct BvhNode {
    vec3 aabb_min;
    uint left_first;
    vec3 aabb_max;
    uint tri_count;
};

// A triangle in BVH order; floatBitsToUint(v0.w) is its index before reordering.
struct BvhTri {
    vec4 v0;
    vec4 v1;
    vec4 v2;
};

// A ray for trace.comp (tests and the ray-throughput benchmark).
struct TraceRay {
    vec4 origin_tmin;
    vec4 dir_tmax;
};

// trace.comp's answer: tri == 0xffffffff for a miss; any-hit mode writes t = 0 or 1 only.
struct TraceHit {
    float t;
    uint tri;
    float u;
    float v;
};

// Push constants of trace.comp.
struct TraceParams {
    uint count;
    uint pad0;
    uint pad1;
    uint pad2;
};

#endif
