// Radiance along a gather ray: what the probe update (probe_trace.comp) and the lightmap bake
// (lightmap_bake.comp) record per ray. A miss brings the environment; a hit brings the light its
// surface reflects back along the ray, shaded with the path tracer's BSDF and lights
// (shading.glsl): direct light from the punctual lights and one emissive-triangle sample with
// shadow rays, plus the probe volume's irradiance at the hit through the diffuse lobe (further
// bounces; the volume of the previous update, or none: its states all inactive). The hit's own
// emission is left out: emitters are direct light, which the lighting pass (and the lightmaps'
// `emitters` layer) samples itself. An unlit surface (KHR_materials_unlit) brings its base
// colour, as in the path tracer, where it is an emitter no light sampling finds. Transmission is
// not modelled: a transmissive surface reflects only. A back face of a single-sided material
// reflects nothing and reports itself.
//
// The including kernel includes random.glsl, gbuffer.glsl, environment.glsl, shading.glsl and
// probes.glsl first.
#ifndef UMBRA_GATHER_GLSL
#define UMBRA_GATHER_GLSL

// Random-number streams of a gather ray (rand4's sample index is the caller's).
const uint RNG_GATHER_EMISSIVE = 0u;
const uint RNG_GATHER_PUNCTUAL = 1u;

// Radiance arriving at `origin` from direction `dir` (unit) under environment `env` (the constant
// or the map's multiplier). `back_face` says whether the ray hit a single-sided back face; `t` is
// the hit distance (BVH_INF on a miss). key / sample / seed pick the random numbers.
vec3 gather_radiance(vec3 origin, vec3 dir, vec3 env, uvec2 env_size, uint light_count, uint punctual_count,
                     uvec2 key, uint sample_index, uint seed, out bool back_face, out float t) {
    back_face = false;
    t = BVH_INF;
    Hit hit;
    if (!bvh_closest(origin, dir, 0.0, BVH_INF, hit)) {
        if (HAS_ENV_MAP) {
            env *= env_radiance(dir, env_size);
        }
        return env;
    }
    t = hit.t;
    uint tri = hit.tri;
    vec3 ng = normalize(hit_normal(hit));
    vec3 wo = -dir;
    uint material = tri_material(tri);
    bool two_sided = material_flag(material, MATERIAL_DOUBLE_SIDED);
    bool front = dot(ng, wo) >= 0.0;
    if (!front && !two_sided) {
        back_face = true;
        return vec3(0.0);
    }
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
    s.base *= tri_color(tri, hit.bary).rgb;
    if (coat_normal_differs()) {
        surface_coat_normal(s, coat_normal_lod(tri, hit.bary, ng, uv, LOD_LEVEL0), tt, bt, n);
    }
    if (material_unlit(material)) {
        return s.base;
    }
    vec3 radiance = vec3(0.0);
    if (wo_local.z <= 0.0) {
        return radiance;
    }
    if (HAS_PUNCTUAL) {
        float u = rand4(key, sample_index, RNG_GATHER_PUNCTUAL, seed).x;
        radiance += punctual_direct(p, ng, tt, bt, n, s, wo_local, punctual_count, u);
    }
    if (HAS_LIGHTS && light_count > 0u) {
        vec4 u = rand4(key, sample_index, RNG_GATHER_EMISSIVE, seed);
        vec3 wi_local;
        vec3 l_emit;
        float light_pdf;
        if (sample_emissive(p, ng, tt, bt, n, false, u.xyz, light_count, wi_local, l_emit, light_pdf)) {
            radiance += bsdf_eval(s, wo_local, wi_local) * abs(wi_local.z) * l_emit / light_pdf;
        }
    }
    // The diffuse lobe's albedo (bsdf_eval's dielectric diffuse term, its Fresnel at the viewing
    // angle) times irradiance / pi.
    float diffuse = (1.0 - max3(dielectric_fresnel(s, wo_local.z))) * (1.0 - s.metallic);
    radiance += diffuse * s.base * INV_PI * probe_volume_irradiance(p, n, wo);
    return radiance;
}

#endif
