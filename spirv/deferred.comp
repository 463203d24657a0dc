#version 460
// Deferred lighting of the G-buffer (gbuffer.comp) with the path tracer's BSDF and lights:
// emission, punctual lights and emissive triangles with ray-traced shadows (area lights sampled,
// `shadow_rays` shadow rays per pixel, so shadows are soft), and split-sum image-based lighting
// (ibl.glsl; `ibl`) multiplied by ambient occlusion; with a probe volume (`probes`,
// probes.glsl), indirect diffuse light from the probes. Without probes, no indirect light beyond
// what IBL approximates.
// Transmissive materials (KHR_materials_transmission) transmit the prefiltered environment seen
// through their one interface: straight on for thin-walled ones, refracted once for volumes (no
// exit refraction, no second surface: the G-buffer knows only the first), once per colour
// channel for a dispersive volume (KHR_materials_dispersion).
#extension GL_GOOGLE_include_directive : require
#include "kernel/deferred.glsl"
#include "pixel.glsl"

KERNEL_LOCAL_SIZE;

#include "random.glsl"
#include "gbuffer.glsl"
#include "environment.glsl"
const bool GGX_WALTER = false;  // the BSDF is evaluated here, never sampled
#define UMBRA_SHADOW_MAPS
#include "shading.glsl"
#include "shadow.glsl"
#include "ibl.glsl"
#include "probes.glsl"
#include "restir.glsl"

// Shadow maps instead of shadow rays for the punctual lights (src/passes/shadow.rs).
float punctual_shadow(uint k, vec3 p, vec3 ng, vec3 wi) {
    return shadow_map_visibility(k, p, ng, wi, params.camera.origin, params.camera.forward, gl_GlobalInvocationID.xy);
}

// Ray-traced shadows of sized lights (shadow.glsl), `shadow_rays` rays per light and pixel.
float punctual_sized_shadow(uint k, vec3 p, vec3 ng, vec3 wi, bool to_point, vec3 position) {
    return sized_light_visibility(k, p, ng, wi, to_point, position, params.light_radius, params.sun_one_minus_cos,
                                  max(params.shadow_rays, 1u), params.frame, params.seed, gl_GlobalInvocationID.xy);
}

// The punctual light pick's stream (the emissive samples draw from RNG_EMISSIVE_NEE).
const uint RNG_DEFERRED_PUNCTUAL = 2u;

// The BRDF table (A, B, C, D) at (n.v, perceptual roughness), bilinear between its entries (n.v
// at texel centres, roughness j / (N - 1)).
vec4 ibl_table(float nv, float roughness) {
    float n = float(IBL_LUT_SIZE);
    vec2 p = clamp(vec2(nv * n - 0.5, roughness * (n - 1.0)), vec2(0.0), vec2(n - 1.0));
    uvec2 i0 = uvec2(p);
    uvec2 i1 = min(i0 + 1u, uvec2(IBL_LUT_SIZE - 1u));
    vec2 f = p - vec2(i0);
    vec4 a = mix(ibl_lut[i0.y * IBL_LUT_SIZE + i0.x], ibl_lut[i0.y * IBL_LUT_SIZE + i1.x], f.x);
    vec4 b = mix(ibl_lut[i1.y * IBL_LUT_SIZE + i0.x], ibl_lut[i1.y * IBL_LUT_SIZE + i1.x], f.x);
    return mix(a, b, f.y);
}

// Material `material`'s lightmap (its ambient layer, src/passes/lightmap.rs) at UV1 `uv`,
// bilinear with the texel centres at (i + 1/2) / size, clamped at the map's edges; false when the
// material has no map.
bool lightmap_irradiance(uint material, vec2 uv, out vec3 e) {
    e = vec3(0.0);
    vec4 header = imageLoad(lightmap_texels, 0);
    uint materials = uint(header.y);
    if (material >= materials) {
        return false;
    }
    uint map = uint(imageLoad(lightmap_texels, int(1u + material)).x);
    if (map == 0u) {
        return false;
    }
    uint size = uint(header.x);
    int base = int(1u + materials + (map - 1u) * size * size);
    vec2 p = clamp(uv * float(size) - 0.5, vec2(0.0), vec2(float(size) - 1.0));
    uvec2 i0 = uvec2(p);
    uvec2 i1 = min(i0 + 1u, uvec2(size - 1u));
    vec2 f = p - vec2(i0);
    vec3 a = mix(imageLoad(lightmap_texels, base + int(i0.y * size + i0.x)).rgb,
                 imageLoad(lightmap_texels, base + int(i0.y * size + i1.x)).rgb, f.x);
    vec3 b = mix(imageLoad(lightmap_texels, base + int(i1.y * size + i0.x)).rgb,
                 imageLoad(lightmap_texels, base + int(i1.y * size + i1.x)).rgb, f.x);
    e = mix(a, b, f.y);
    return true;
}

// Prefiltered level k at direction r: level 0 is the map itself (nearest, as env_radiance).
vec3 ibl_level(uint k, vec3 r) {
    uvec2 src = params.env_size;
    if (k == 0u) {
        return env_radiance(r, src);
    }
    uvec4 idx;
    vec4 w;
    equirect_taps(env_uv(r), ibl_level_size(k, src), idx, w);
    uint o = ibl_level_offset(k, src);
    return w.x * ibl_prefiltered[o + idx.x].rgb + w.y * ibl_prefiltered[o + idx.y].rgb +
           w.z * ibl_prefiltered[o + idx.z].rgb + w.w * ibl_prefiltered[o + idx.w].rgb;
}

// The prefiltered environment along r for a lobe of `roughness`: the two chain levels around
// it, blended.
vec3 prefiltered_light(vec3 r, float roughness) {
    float lod = clamp(roughness, 0.0, 1.0) * float(IBL_LEVELS - 1u);
    uint k0 = min(uint(lod), IBL_LEVELS - 1u);
    uint k1 = min(k0 + 1u, IBL_LEVELS - 1u);
    return mix(ibl_level(k0, r), ibl_level(k1, r), lod - float(k0));
}

// Split-sum image-based lighting of surface s at shading normal n seen along wo (world), nv =
// n.wo > 0: the prefiltered environment times the table's specular albedo, plus the diffuse
// colour times irradiance / pi times the table's diffuse Fresnel weighting, blended by metallic
// as bsdf_eval blends.
//
// With an irradiance probe volume (PROBES), its irradiance at p replaces the environment's as the
// diffuse lobe's light: it carries the environment with its occlusion and the light that
// surfaces reflect (src/passes/probes.rs); the specular and transmitted parts stay the split
// sum's, and without `ibl` only the probes' diffuse light remains. A material with a lightmap
// (LIGHTMAPS) takes its ambient irradiance at UV1 `uv1` instead of both. A clear coat reflects
// about its own normal `coat_n` (world).
//
// The environment's light is occluded by `env_occlusion` (ambient occlusion and the material's
// occlusion map); the probes' and lightmaps' irradiance by `baked_occlusion` alone (the
// occlusion map's): their bake already holds the geometry's occlusion of that light, and screen-
// space AO on top darkens it twice.
vec3 ibl_lighting(Surface s, float roughness, vec3 p, vec3 n, vec3 wo, float nv, uint material, vec2 uv1,
                  vec3 coat_n, float env_occlusion, float baked_occlusion) {
    // The prefiltered map assumed n = v = r; a rough lobe actually leans from the mirror direction
    // towards the normal: look up along the dominant direction (Lagarde and de Rousiers 2014,
    // "Moving Frostbite to PBR", eq. 56, with alpha as their linear roughness).
    vec3 rn = n;
    if (s.anisotropy > 0.0) {
        // KHR_materials_anisotropy: the Khronos Sample Viewer's bent normal (after Filament): the
        // normal turned towards the plane of the view and the anisotropy bitangent (the lobe's
        // narrow axis), by pow4(1 - strength (1 - roughness)); the prefiltered map then looked up
        // about it at the base roughness (docs/methods.md: its error against the path tracer).
        vec3 t;
        vec3 b;
        basis(n, t, b);
        vec3 aniso_b = cross(n, s.aniso_dir.x * t + s.aniso_dir.y * b);
        vec3 bent = normalize(cross(cross(aniso_b, wo), aniso_b));
        float bend = 1.0 - s.anisotropy * (1.0 - roughness);
        bend *= bend;
        rn = normalize(mix(bent, n, bend * bend));
    }
    vec3 r = reflect(-wo, rn);
    if (params.ibl_dominant != 0u) {
        float smooth_ = clamp(1.0 - s.alpha, 0.0, 1.0);
        r = normalize(mix(rn, r, smooth_ * (sqrt(smooth_) + s.alpha)));
    }
    vec4 table = ibl_table(nv, roughness);
    vec3 env = params.ibl != 0u ? params.env * env_occlusion : vec3(0.0);
    vec3 specular_light = env;
    vec3 irradiance_over_pi = env;
    vec3 transmitted_light = env;
    // Transmission: the view ray continues through a thin wall, or refracts into a volume
    // (total internal reflection cannot happen entering the denser medium from outside).
    vec3 through = s.thin ? -wo : refract(-wo, n, 1.0 / s.eta);
    if (HAS_ENV_MAP && params.ibl != 0u) {
        specular_light *= prefiltered_light(r, roughness);
        if (surface_transmits(s) && dot(through, through) > 0.0) {
            float dispersion = s.thin ? 0.0 : material_dispersion(material);
            if (dispersion > 0.0) {
                // KHR_materials_dispersion: each colour channel refracted at its own index of
                // refraction (the Sample Viewer's method, at the extension's Cauchy fit).
                for (uint c = 0u; c < 3u; ++c) {
                    vec3 through_c = refract(-wo, n, 1.0 / dispersed_ior(s.eta, dispersion, c));
                    transmitted_light[c] *= prefiltered_light(through_c, roughness)[c];
                }
            } else {
                transmitted_light *= prefiltered_light(through, roughness);
            }
        }
        float y[9];
        sh9_basis(n, y);
        vec3 e = vec3(0.0);
        for (uint k = 0u; k < 9u; ++k) {
            e += ibl_sh[k].rgb * y[k];
        }
        irradiance_over_pi *= max(e, vec3(0.0)) * INV_PI;
    }
    // KHR_materials_diffuse_transmission's light: the irradiance behind the surface, the
    // environment's at -n (the probes and lightmaps hold the front's only).
    vec3 back_over_pi = env;
    if (HAS_ENV_MAP && params.ibl != 0u && s.diffuse_transmission > 0.0) {
        float y[9];
        sh9_basis(-n, y);
        vec3 e = vec3(0.0);
        for (uint k = 0u; k < 9u; ++k) {
            e += ibl_sh[k].rgb * y[k];
        }
        back_over_pi *= max(e, vec3(0.0)) * INV_PI;
    }
    if (PROBES) {
        irradiance_over_pi = probe_volume_irradiance(p, n, wo) * (INV_PI * baked_occlusion);
    }
    if (LIGHTMAPS) {
        vec3 e;
        if (lightmap_irradiance(material, uv1, e)) {
            irradiance_over_pi = e * (INV_PI * baked_occlusion);
        }
    }
    vec3 dielectric_spec = s.f0 * table.x + s.f90 * table.y;
    float diffuse_weight = 1.0 - max3(s.f0) * table.z - s.f90 * table.w;
    vec3 metal_spec = s.base * table.x + table.y;
    if (s.iridescence > 0.0) {
        // KHR_materials_iridescence: the film's Fresnel taken at n.v for the whole lobe (as the
        // Sample Viewer does), times the lobe's albedo A + B; the diffuse lobe keeps 1 - max3(F)
        // of the mixed Fresnel (C + D: the table's diffuse weighting of a constant F). The path
        // tracer takes it at each microfacet's v.h (tests/ibl/ measures the difference).
        vec3 film = iridescent_fresnel(s.iridescence_ior, s.iridescence_thickness, s.f0, nv);
        vec3 film_metal = iridescent_fresnel(s.iridescence_ior, s.iridescence_thickness, s.base, nv);
        dielectric_spec = mix(dielectric_spec, film * (table.x + table.y), s.iridescence);
        diffuse_weight = 1.0 - max3(mix(s.f0 * table.z + s.f90 * table.w, film * (table.z + table.w), s.iridescence));
        metal_spec = mix(metal_spec, film_metal * (table.x + table.y), s.iridescence);
    }
    if (HAS_TRANSMISSION) {
        // KHR_materials_volume's attenuation, approximated as the Khronos Sample Viewer does:
        // Beer-Lambert over the material's thickness (thicknessFactor x thicknessTexture, in the
        // mesh's units), whatever the view angle; 1 without a volume (no thickness, no
        // attenuation coefficient).
        transmitted_light *= exp(-material_attenuation(material) * s.thickness);
    }
    // The diffuse lobe's share `transmission` transmits instead (as bsdf.glsl splits it).
    vec3 below = mix(irradiance_over_pi, transmitted_light, s.transmission);
    vec3 dielectric = dielectric_spec * specular_light + diffuse_weight * s.base * below;
    if (s.diffuse_transmission > 0.0) {
        // KHR_materials_diffuse_transmission: its share of the diffuse lobe (what transmission
        // leaves of it) lit from behind instead, tinted by its colour (as bsdf.glsl splits it).
        dielectric += diffuse_weight * (1.0 - s.transmission) * s.diffuse_transmission
            * (s.diffuse_transmission_color * back_over_pi - s.base * irradiance_over_pi);
    }
    vec3 metal = metal_spec * specular_light;
    vec3 result = mix(dielectric, metal, s.metallic);
    if (max3(s.sheen) > 0.0) {
        // KHR_materials_sheen: the material scaled by the sheen's albedo scaling at n.v alone
        // (the extension's simplified form), and the sheen's albedo E(n.v) lit by the diffuse
        // irradiance (its lobe is broad; tests/ibl/ measures the approximation).
        float e = sheen_albedo(nv, s.sheen_roughness);
        result = max(0.0, 1.0 - max3(s.sheen) * e) * result + s.sheen * e * irradiance_over_pi;
    }
    if (s.coat > 0.0) {
        // KHR_materials_clearcoat: the coat's lobe (its own roughness, no Fresnel inside: the
        // table's albedo at F0 = F90 = 1) over the base, weighted as bsdf_eval weighs them.
        float coat_roughness = sqrt(s.coat_alpha);
        vec3 cn = n;
        float cnv = nv;
        if (coat_normal_differs()) {
            cn = coat_n;
            cnv = max(dot(coat_n, wo), 0.0);
        }
        vec4 coat_table = ibl_table(cnv, coat_roughness);
        vec3 coat_light = env;
        if (HAS_ENV_MAP && params.ibl != 0u) {
            coat_light *= prefiltered_light(reflect(-wo, cn), coat_roughness);
        }
        float w = coat_weight_at(s.coat, cnv);
        result = (1.0 - w) * result + w * (coat_table.x + coat_table.y) * coat_light;
    }
    return result;
}

// Direct light by power sampling: every punctual light (up to PUNCTUAL_ALL) with its shadow ray,
// and `shadow_rays` samples of the emissive triangles.
vec3 power_sampled_light(vec3 p, vec3 ng, vec3 t, vec3 b, vec3 n, Surface s, vec3 wo_local, ivec2 pixel) {
    vec3 radiance = vec3(0.0);
    // Punctual lights: one shadow ray each.
    if (HAS_PUNCTUAL) {
        float u = rand4(uvec2(pixel), params.frame, RNG_DEFERRED_PUNCTUAL, params.seed).x;
        radiance += punctual_direct(p, ng, t, b, n, s, wo_local, params.punctual_count, u);
    }

    // Emissive triangles: `shadow_rays` light samples (triangle by power, uniform point on it),
    // each with its shadow ray; light sampling alone, which is unbiased for direct light.
    if (HAS_LIGHTS && params.light_count > 0u) {
        uint rays = max(params.shadow_rays, 1u);
        vec3 sum = vec3(0.0);
        for (uint r = 0u; r < rays; ++r) {
            vec4 u = rand4(uvec2(pixel), params.frame * rays + r, RNG_EMISSIVE_NEE, params.seed);
            vec3 wi_local;
            vec3 l_emit;
            float light_pdf;
            if (sample_emissive(p, ng, t, b, n, surface_transmits(s), u.xyz, params.light_count, wi_local, l_emit,
                                light_pdf)) {
                sum += bsdf_eval(s, wo_local, wi_local) * abs(wi_local.z) * l_emit / light_pdf;
            }
        }
        radiance += sum / float(rays);
    }
    return radiance;
}

void main() {
    ivec2 pixel = ivec2(tile_pixel());
    uvec2 size = params.size;
    if (any(greaterThanEqual(uvec2(pixel), size))) {
        return;
    }
    ShadePoint sp;
    if (!gbuffer_point(pixel, sp)) {
        // No surface: the environment seen directly.
        vec3 origin;
        vec3 dir;
        camera_ray(params.camera.origin, params.camera.forward, params.camera.right, params.camera.up,
                   camera_orthographic(params.camera.flags), camera_sample(pixel, params.camera.flags), size, origin, dir);
        vec3 background = params.env;
        if (HAS_ENV_MAP) {
            background *= env_radiance(dir, params.env_size);
        }
        imageStore(out_color, pixel, vec4(background, 1.0));
        return;
    }
    vec3 radiance = imageLoad(gb_emission, pixel).rgb;
    // KHR_materials_unlit: the base colour (factor x texture x COLOR_0) as it is, no lighting.
    if (material_unlit(sp.material)) {
        imageStore(out_color, pixel, vec4(sp.s.base, 1.0));
        return;
    }
    // Parallax occlusion mapping: the G-buffer's primary ray again, marched into the height field
    // by the same function, for the self-shadowing of the light samples below (light_side; under
    // ReSTIR through restir_contribution's light_side: the ReSTIR kernels themselves are not
    // specialised for parallax, as they read their neighbours' G-buffer points).
    if (HAS_PARALLAX) {
        if (material_slot_texture(sp.material, MATERIAL_SLOT_HEIGHT) != 0u) {
            vec3 origin;
            vec3 dir;
            camera_ray(params.camera.origin, params.camera.forward, params.camera.right, params.camera.up,
                       camera_orthographic(params.camera.flags), camera_sample(pixel, params.camera.flags), size, origin, dir);
            Hit hit;
            if (bvh_closest(origin, dir, 0.0, BVH_INF, hit)) {
                parallax_occlusion(hit.tri, hit.bary, sp.wo);
            }
        }
    }
    if (sp.wo_local.z > 0.0) {
        Surface s = sp.s;
        // Image-based lighting (split sum) and the probes' irradiance, times ambient occlusion.
        bool ambient = params.ibl != 0u;
        if (PROBES) {
            ambient = true;
        }
        if (LIGHTMAPS) {
            ambient = true;
        }
        if (ambient) {
            float ao = imageLoad(ao_image, min(pixel, imageSize(ao_image) - 1)).x;
            // The material's occlusion map (glTF occlusionTexture): ambient light only (the
            // probes' indirect light too, as glTF says of indirect light). It and the ambient
            // occlusion estimate one occlusion, baked and on screen: the smaller of the two (as
            // Filament combines them), not their product, which counts it twice.
            float occlusion = imageLoad(gb_emission, pixel).a;
            radiance += ibl_lighting(s, sp.roughness, sp.p, sp.n, sp.wo, sp.wo_local.z, sp.material, sp.uv1,
                                     sp.t * s.coat_n.x + sp.b * s.coat_n.y + sp.n * s.coat_n.z,
                                     min(ao, occlusion), occlusion);
        }

        // ReSTIR DI (restir.glsl): the pixel's reservoir's one light sample, its shadow ray, its
        // unbiased contribution weight, for the punctual lights and the emissive triangles.
        if (RESTIR) {
            uint index = uint(pixel.y) * size.x + uint(pixel.x);
            uint id = reservoirs[index].light;
            vec2 bary = reservoirs[index].bary;
            float w = reservoirs[index].weight;
            bool tested = (reservoirs[index].flags & RESTIR_VISIBLE) != 0u;
            vec3 wi;
            bool to_point;
            vec3 target;
            vec3 c = restir_contribution(sp, id, bary, wi, to_point, target);
            if (w > 0.0 && any(greaterThan(c, vec3(0.0)))) {
                // The reservoir's weight includes a ray-traced visibility (the biased combination),
                // or this pass finds it; shadow maps, when the pass reads them, shadow the
                // punctual lights either way.
                float visible = tested ? 1.0 : 0.0;
                bool punctual = (id & RESTIR_PUNCTUAL) != 0u;
                bool mapped = false;
                if (SHADOW_MAPS) {
                    mapped = punctual;
                }
                if (mapped || !tested) {
                    if (punctual) {
                        vec3 wi_local;
                        visible = punctual_visibility(id & ~RESTIR_PUNCTUAL, sp.p, sp.ng, sp.t, sp.b, sp.n,
                                                      surface_transmits(s), wi, to_point, target, wi_local);
                    } else {
                        visible = restir_visible(sp, wi, to_point, target) ? 1.0 : 0.0;
                    }
                }
                radiance += c * (visible * w);
            }
        } else {
            radiance += power_sampled_light(sp.p, sp.ng, sp.t, sp.b, sp.n, s, sp.wo_local, pixel);
        }
    }
    imageStore(out_color, pixel, vec4(radiance, 1.0));
}
