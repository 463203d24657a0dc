#version 460
// One update of a range of irradiance probes, first half (src/passes/probes.rs): every probe
// casts `rays` rays (a rotated spherical Fibonacci set, probes.glsl) through the BVH and records
// per ray the radiance coming back (gather.glsl: the environment, or the light the hit surface
// reflects, with the volume's irradiance of the previous update as the further bounces: one more
// bounce each update) and the distance to the hit. A back face (of a single-sided material)
// records a fifth of its distance as a negative number: the probe may be inside geometry
// (probe_blend counts them) and sees that surface nearer than it is.
#extension GL_GOOGLE_include_directive : require
#include "kernel/probe_trace.glsl"

KERNEL_LOCAL_SIZE;

const bool BECKMANN = false;
const bool GGX_WALTER = false;

#include "random.glsl"
#include "gbuffer.glsl"
#include "environment.glsl"
#include "shading.glsl"
#include "probes.glsl"
#include "gather.glsl"

void main() {
    uint ray = gl_GlobalInvocationID.x;
    uint slot = gl_GlobalInvocationID.y;
    uint rays = params.rays;
    if (ray >= rays || slot >= params.probe_count) {
        return;
    }
    uvec3 counts = probe_counts();
    uint total = counts.x * counts.y * counts.z;
    uint probe = (params.first_probe + slot) % total;
    vec3 origin = probe_position(probe);
    vec3 dir = probe_ray_direction(ray, rays, params.rotation0.xyz, params.rotation1.xyz, params.rotation2.xyz);
    bool back_face;
    float t;
    vec3 radiance = gather_radiance(origin, dir, params.env, params.env_size, params.light_count,
                                    params.punctual_count, uvec2(ray, probe), params.seed, 0u, back_face, t);
    t = min(t, params.max_distance);
    probe_rays[slot * rays + ray] = vec4(radiance, back_face ? -0.2 * t : t);
}
