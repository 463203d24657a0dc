#version 460
// Shadow maps: each tile's first list entry, an exclusive prefix sum of the counts
// shadow_bin.comp made (one workgroup; each invocation sums a run of tiles, the workgroup scans
// the runs), the counts set back to 0 for the fill, and the need reported.
#extension GL_GOOGLE_include_directive : require
#include "kernel/shadow_scan.glsl"

KERNEL_LOCAL_SIZE;

shared uint runs[256];

void main() {
    uint lane = gl_LocalInvocationIndex;
    uint tiles = params.tiles * params.tiles;
    uint per = (tiles + 255u) / 256u;
    uint begin = min(lane * per, tiles);
    uint end = min(begin + per, tiles);
    uint sum = 0u;
    uint fullest = 0u;
    for (uint t = begin; t < end; ++t) {
        sum += tile_count[t];
        fullest = max(fullest, tile_count[t]);
    }
    runs[lane] = sum;
    barrier();
    // Inclusive scan of the runs (Hillis and Steele).
    for (uint step = 1u; step < 256u; step <<= 1u) {
        uint add = lane >= step ? runs[lane - step] : 0u;
        barrier();
        runs[lane] += add;
        barrier();
    }
    uint start = lane > 0u ? runs[lane - 1u] : 0u;
    for (uint t = begin; t < end; ++t) {
        uint count = tile_count[t];
        tile_start[t] = start;
        tile_count[t] = 0u;
        start += count;
    }
    atomicMax(stats.tile_max, fullest);
    if (lane == 255u) {
        atomicMax(stats.entries, runs[255]);
    }
}
