#version 460
// One update of a range of irradiance probes, first half (src/passes/probes.rs): every probe
// casts `rays` rays (a rotated spherical Fibonacci set, probes.glsl) through the BVH and records
// per ray the radiance coming back and the distance to the hit. The radiance is what the lighting
// pass does not compute itself: a miss brings the environment; a hit brings the light its surface
// reflects towards the probe, shaded with the path tracer's BSDF and lights (shading.glsl):
// direct light from the punctual lights and one emissive-triangle sample with shadow rays, plus
// the volume's irradiance at the hit (the previous update: one more bounce each update) through
// the surface's diffuse lobe. A hit's own emission is left out: the lighting pass
// samples emitters as direct light. A back face (of a single-sided material) records no light and
// a fifth of its distance as a negative number: the probe may be inside geometry (probe_blend
// counts them) and sees that surface nearer than it is. Transmission is not modelled: a
// transmissive surface reflects only.
#extension GL_GOOGLE_include_directive : require
#include "kernel/probe_trace.glsl"

layout(local_size_x = 64) in;

const bool BECKMANN = false;
const bool GGX_WALTER = false;

#include "random.glsl"
#include "gbuffer.glsl"
#include "environment.glsl"
#include "shading.glsl"
#include "probes.glsl"

// Random-number streams of a probe ray (rand4's sample index is the update's seed).
const uint RNG_PROBE_EMISSIVE = 0u;
const uint RNG_PROBE_PUNCTUAL = 1u;

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
    uvec2 key = uvec2(ray, probe);

    vec4 result;
    Hit hit;
    if (!bvh_closest(origin, dir, 0.0, BVH_INF, hit)) {
        vec3 env = params.env;
        if (HAS_ENV_MAP) {
            env *= env_radiance(dir, params.env_size);
        }
        result = vec4(env, params.max_distance);
    } else {
        uint tri = hit.tri;
        vec3 ng = normalize(tri_normal(tri));
        vec3 wo = -dir;
        uint material = tri_material(tri);
        bool two_sided = (material_uvec(material, 4u).x & MATERIAL_DOUBLE_SIDED) != 0u;
        bool front = dot(ng, wo) >= 0.0;
        float t = min(hit.t, params.max_distance);
        if (!front && !two_sided) {
            result = vec4(0.0, 0.0, 0.0, -0.2 * t);
        } else {
            if (!front) {
                ng = -ng;
            }
            vec3 p = origin + hit.t * dir;
            vec4 uv = tri_uv(tri, hit.bary);
            vec3 n = shading_normal(tri, hit.bary, ng, uv);
            vec3 tt;
            vec3 bt;
            basis(n, tt, bt);
            vec3 wo_local = vec3(dot(wo, tt), dot(wo, bt), dot(wo, n));
            Surface s = material_surface(material, uv);
            vec3 radiance = vec3(0.0);
            if (wo_local.z > 0.0) {
                if (HAS_PUNCTUAL) {
                    float u = rand4(key, params.seed, RNG_PROBE_PUNCTUAL, 0u).x;
                    radiance += punctual_direct(p, ng, tt, bt, n, s, wo_local, params.punctual_count, u);
                }
                if (HAS_LIGHTS && params.light_count > 0u) {
                    vec4 u = rand4(key, params.seed, RNG_PROBE_EMISSIVE, 0u);
                    vec3 wi_local;
                    vec3 l_emit;
                    float light_pdf;
                    if (sample_emissive(p, ng, tt, bt, n, false, u.xyz, params.light_count, wi_local, l_emit, light_pdf)) {
                        radiance += bsdf_eval(s, wo_local, wi_local) * abs(wi_local.z) * l_emit / light_pdf;
                    }
                }
                // The diffuse lobe's albedo (bsdf_eval's dielectric diffuse term, its Fresnel at the
                // viewing angle) times irradiance / pi.
                float diffuse = (1.0 - max3(dielectric_fresnel(s, wo_local.z))) * (1.0 - s.metallic);
                radiance += diffuse * s.base * INV_PI * probe_volume_irradiance(p, n, wo);
            }
            result = vec4(radiance, t);
        }
    }
    probe_rays[slot * rays + ray] = result;
}
