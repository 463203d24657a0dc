#version 460
// Traces a buffer of rays through the BVH: closest hit (TRACE_ANY == 0) or any hit (1).
// Used by the traversal tests and by umbra-bench's ray-throughput mode.
#extension GL_GOOGLE_include_directive : require
#include "kernel/trace.glsl"

KERNEL_LOCAL_SIZE;

#include "bvh.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) {
        return;
    }
    vec4 origin_tmin = rays[i].origin_tmin;
    vec4 dir_tmax = rays[i].dir_tmax;
    // Members one by one: whole-struct copies to and from buffers are OpCopyLogical (naga).
    vec4 result = vec4(0.0, uintBitsToFloat(0xffffffffu), 0.0, 0.0);
    if (TRACE_ANY) {
        if (bvh_any(origin_tmin.xyz, dir_tmax.xyz, origin_tmin.w, dir_tmax.w)) {
            result = vec4(1.0, 0.0, 0.0, 0.0);
        }
    } else {
        Hit hit;
        if (bvh_closest(origin_tmin.xyz, dir_tmax.xyz, origin_tmin.w, dir_tmax.w, hit)) {
            result = vec4(hit.t, uintBitsToFloat(hit.tri), hit.bary);
        } else {
            // A miss: how many implicit-shape marches ran out of steps (0 without shapes).
            result.z = float(implicit_marches_exhausted);
        }
    }
    hits[i].t = result.x;
    hits[i].tri = floatBitsToUint(result.y);
    hits[i].u = result.z;
    hits[i].v = result.w;
}
