#version 460
// SH9 irradiance of the environment map (ibl.glsl): one workgroup per dispatch, 128 rows from
// params.first_row (one row per invocation: the basis integrated exactly over each texel,
// sh9_cell), a tree reduction per coefficient, multiplied by A_l and added to what the earlier
// dispatches summed (the first one writes). Rows in batches because llvmpipe breaks every loop
// of an invocation after 65,535 loop iterations in all: one invocation summing every 128th row
// of a 4096×2048 map went past it and left the coefficients 98 % off.
#extension GL_GOOGLE_include_directive : require
#include "kernel/ibl_sh.glsl"

KERNEL_LOCAL_SIZE;

#include "environment.glsl"
#include "ibl.glsl"

shared vec3 partial[128];

void main() {
    uint tid = gl_LocalInvocationID.x;
    uvec2 size = params.src_size;
    vec3 c[9];
    for (uint k = 0u; k < 9u; ++k) {
        c[k] = vec3(0.0);
    }
    for (uint y = params.first_row + tid; y < min(params.first_row + 128u, size.y); y += 128u) {
        float t0 = PI * float(y) / float(size.y);
        float t1 = PI * float(y + 1u) / float(size.y);
        for (uint x = 0u; x < size.x; ++x) {
            float p0 = (float(x) / float(size.x) - 0.5) * 2.0 * PI;
            float p1 = (float(x + 1u) / float(size.x) - 0.5) * 2.0 * PI;
            float cell[9];
            sh9_cell(t0, t1, p0, p1, cell);
            vec3 l = env_value(y * size.x + x).rgb;
            for (uint k = 0u; k < 9u; ++k) {
                c[k] += l * cell[k];
            }
        }
    }
    for (uint k = 0u; k < 9u; ++k) {
        partial[tid] = c[k];
        barrier();
        for (uint s = 64u; s > 0u; s >>= 1u) {
            if (tid < s) {
                partial[tid] += partial[tid + s];
            }
            barrier();
        }
        if (tid == 0u) {
            vec3 before = params.first_row > 0u ? sh[k].rgb : vec3(0.0);
            sh[k] = vec4(before + partial[0] * sh9_band_factor(k), 0.0);
        }
        barrier();
    }
}
