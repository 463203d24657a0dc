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

#endif
