#version 460
// Bits of the branches taken on two specialization constants, in each form glslang emits them
// for umbra's kernels; the host recomputes them (tests/foundation.rs). What the folding of
// src/vk/specialize.rs must keep exactly.
#extension GL_GOOGLE_include_directive : require
#include "kernel/fold_test.glsl"

KERNEL_LOCAL_SIZE;

// Called only on one side of a folded branch: its body is what the folding keeps from the driver.
uint fold_helper(uint v) {
    uint h = v;
    for (uint k = 0u; k < (v & 3u); k++) {
        h = h * 2654435761u + 1u;
    }
    return (h & 1u) << 9;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) {
        return;
    }
    uint v = values_in[i];
    uint r = 0u;
    if (FLAG_A) {
        r |= 1u;
    }
    if (FLAG_A) {
    } else {
        r |= 2u;
    }
    if (FLAG_A && (v & 1u) == 1u) {
        r |= 4u;
    }
    if ((v % 3u) == 0u || FLAG_B) {
        r |= 8u;
    }
    if (FLAG_B || (v % 5u) == 0u) {
        r |= 16u;
    }
    bool c = FLAG_A && v > 5u;
    if (!c) {
        r |= 32u;
    }
    if (FLAG_A) {
        if (FLAG_B) {
            r |= 64u;
        } else {
            r |= 128u;
        }
    } else if (v > 100u) {
        r |= 256u;
    }
    if (FLAG_B) {
        r |= fold_helper(v);
    }
    values_out[i] = r + params.add;
}
