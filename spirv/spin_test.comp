#version 460
// Test-only: a kernel that hangs on purpose, for the GPU breadcrumb test (tests/reliability.rs).
// Every invocation spins until the host sets `release` to non-zero in a host-visible, coherent
// buffer, re-reading it with an atomic each iteration, and gives up after MAX_ITERATIONS, so the
// kernel can never hang forever. It records how it ended: `spun` = iterations of all
// invocations, `released` = 1 when an invocation saw the host's release.
//
// lavapipe (gallivm) ends an invocation's loops after 65535 iterations in all, whatever the
// bound, so there the length of the hang comes from the number of workgroups. Its SIMD lanes
// are 8 wide and a lane outside the workgroup never sees an atomic's result (it would spin to
// that limit after the release): the workgroup size is a multiple of 8.
#extension GL_GOOGLE_include_directive : require
// MAX_ITERATIONS, a specialization constant, defaults to the bound where loops are not cut short:
// 2^24 atomic reads per invocation.
#include "kernel/spin_test.glsl"

KERNEL_LOCAL_SIZE;

void main() {
    uint i = 0u;
    bool freed = false;
    for (; i < MAX_ITERATIONS; i++) {
        if (atomicAdd(spin.release, 0u) != 0u) {
            freed = true;
            break;
        }
    }
    atomicAdd(spin.spun, i);
    atomicMax(spin.released, freed ? 1u : 0u);
}
