#version 460
// Progressive path tracer: one sample per pixel per dispatch, accumulated as a running mean with
// its second moment. Next-event estimation on emissive triangles, BSDF sampling, multiple
// importance sampling (power or balance heuristic), Russian roulette.
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(constant_id = 0) const bool BECKMANN = false;
layout(constant_id = 1) const bool POWER_HEURISTIC = true;
layout(constant_id = 2) const bool HAS_LIGHTS = true;
layout(constant_id = 3) const bool HAS_PUNCTUAL = true;
layout(constant_id = 4) const bool HAS_ENV_MAP = false;
layout(constant_id = 5) const bool HAS_TEXTURES = false;

layout(set = 0, binding = 0, std430) readonly buffer BvhNodes { BvhNode bvh_nodes[]; };
layout(set = 0, binding = 1, std430) readonly buffer BvhTris { BvhTri bvh_tris[]; };
layout(set = 0, binding = 2, std430) readonly buffer Triangles { GpuTriangle triangles[]; };
layout(set = 0, binding = 3, std430) readonly buffer Vertices { GpuVertex vertices[]; };
layout(set = 0, binding = 4, std430) readonly buffer Materials { GpuMaterial materials[]; };
layout(set = 0, binding = 5, std430) readonly buffer Lights { GpuLightTri lights[]; };
layout(set = 0, binding = 6, std430) buffer Accum { vec4 accum[]; };
layout(set = 0, binding = 7, std430) buffer Moment { vec4 moment[]; };
layout(set = 0, binding = 8, std430) buffer Albedo { vec4 aov_albedo[]; };
layout(set = 0, binding = 9, std430) buffer NormalDepth { vec4 aov_normal_depth[]; };
layout(set = 0, binding = 10, std430) buffer Stats { PathStats stats; };
layout(set = 0, binding = 11, std430) readonly buffer Punctual { GpuLight punctual[]; };
layout(set = 0, binding = 12, std430) readonly buffer EnvTexels { vec4 env_texels[]; };
layout(set = 0, binding = 13, std430) readonly buffer EnvMarginal { float env_marginal[]; };
layout(set = 0, binding = 14, std430) readonly buffer EnvConditional { float env_conditional[]; };
layout(set = 0, binding = 15, std430) readonly buffer Textures { GpuTexture textures[]; };
layout(set = 0, binding = 16, std430) readonly buffer Texels { uint texels[]; };
layout(push_constant) uniform Push { PathParams params; };

#include "random.glsl"
#include "bvh.glsl"
#include "bsdf.glsl"
#include "environment.glsl"
#include "texture.glsl"

// Offsets a ray origin off the surface along n by a few ulps (Wächter and Binder, Ray Tracing
// Gems ch. 6), so the new ray neither re-hits its own triangle nor tunnels through a neighbour.
vec3 offset_ray(vec3 p, vec3 n) {
    ivec3 of_i = ivec3(256.0 * n);
    vec3 p_i = intBitsToFloat(floatBitsToInt(p) + mix(of_i, -of_i, lessThan(p, vec3(0.0))));
    return mix(p_i, p + (1.0 / 65536.0) * n, lessThan(abs(p), vec3(1.0 / 32.0)));
}

// Whether light arriving along wi (unit, towards the light) reaches p: wi above both the shading
// frame (t, b, n) and the geometric surface ng, and nothing on the shadow ray, which ends just
// short of `target` when `to_point` and is unbounded otherwise. Also gives wi in the frame.
bool light_reaches(vec3 p, vec3 ng, vec3 t, vec3 b, vec3 n, vec3 wi, bool to_point, vec3 target, out vec3 wi_local) {
    wi_local = vec3(dot(wi, t), dot(wi, b), dot(wi, n));
    if (!(wi_local.z > 0.0 && dot(wi, ng) > 0.0)) {
        return false;
    }
    vec3 o = offset_ray(p, ng);
    return to_point ? !bvh_any(o, target - o, 0.0, 0.9999) : !bvh_any(o, wi, 0.0, BVH_INF);
}

float mis_weight(float a, float b) {
    if (POWER_HEURISTIC) {
        a *= a;
        b *= b;
    }
    return a / (a + b);
}

// Material texture `slot` (0 base colour, 1 metallic-roughness, 2 emissive, 3 normal) at the hit's UV
// sets (uv.xy = uv0, uv.zw = uv1); white when the slot is empty.
vec4 material_texture(uint id, uint slot, vec4 uv) {
    // Spec constants only as plain `if` conditions: `!HAS_TEXTURES` or `?:` on one would be an
    // OpSpecConstantOp, which naga rejects.
    uint tex = 0u;
    if (HAS_TEXTURES) {
        tex = materials[id].textures[slot];
    }
    if (tex == 0u) {
        return vec4(1.0);
    }
    vec4 r0 = materials[id].tex_transform[2u * slot];
    vec4 r1 = materials[id].tex_transform[2u * slot + 1u];
    vec2 st = r0.w != 0.0 ? uv.zw : uv.xy;
    vec2 t = vec2(dot(r0.xyz, vec3(st, 1.0)), dot(r1.xyz, vec3(st, 1.0)));
    return texture_sample(tex - 1u, t);
}

Surface material_surface(uint id, vec4 uv) {
    // Member by member: a whole-struct copy from a buffer is OpCopyLogical, which naga rejects.
    Surface s;
    s.base = materials[id].base_color.rgb * material_texture(id, 0u, uv).rgb;
    vec4 mr = material_texture(id, 1u, uv);
    s.metallic = clamp(materials[id].params.x * mr.b, 0.0, 1.0);
    float r = clamp(materials[id].emissive_rough.w * mr.g, 0.0, 1.0);
    s.alpha = max(r * r, ALPHA_MIN);
    float ior = materials[id].params.y;
    float f0 = (ior - 1.0) / (ior + 1.0);
    s.f0 = min(vec3(f0 * f0) * materials[id].specular.rgb, vec3(1.0)) * materials[id].specular.w;
    s.f90 = materials[id].specular.w;
    return s;
}

vec3 tri_vertex(uint tri, uint k) {
    return k == 0u ? bvh_tris[tri].v0.xyz : (k == 1u ? bvh_tris[tri].v1.xyz : bvh_tris[tri].v2.xyz);
}

// Unnormalised geometric normal (length = 2 * area), by the winding.
vec3 tri_normal(uint tri) {
    vec3 a = bvh_tris[tri].v0.xyz;
    return cross(bvh_tris[tri].v1.xyz - a, bvh_tris[tri].v2.xyz - a);
}

// Both UV sets at barycentrics (b1, b2) of triangle `tri`: uv0 in xy, uv1 in zw.
vec4 tri_uv(uint tri, vec2 bary) {
    vec4 uv = vec4(0.0);
    if (HAS_TEXTURES) {
        uint i0 = triangles[tri].v0;
        uint i1 = triangles[tri].v1;
        uint i2 = triangles[tri].v2;
        vec4 a = vec4(vertices[i0].normal_u.w, vertices[i0].v_uv1.xyz);
        vec4 b = vec4(vertices[i1].normal_u.w, vertices[i1].v_uv1.xyz);
        vec4 c = vec4(vertices[i2].normal_u.w, vertices[i2].v_uv1.xyz);
        uv = (1.0 - bary.x - bary.y) * a + bary.x * b + bary.y * c;
    }
    return uv;
}

// Radiance the triangle emits at barycentrics `bary` towards a viewer on the side of `towards`
// (unit normal n).
vec3 emitted(uint tri, vec2 bary, vec3 n, vec3 towards) {
    uint m = triangles[tri].material;
    bool front = dot(n, towards) > 0.0;
    bool two_sided = (materials[m].flags.x & MATERIAL_DOUBLE_SIDED) != 0u;
    if (!(front || two_sided)) {
        return vec3(0.0);
    }
    vec3 e = materials[m].emissive_rough.rgb;
    if (HAS_TEXTURES && any(greaterThan(e, vec3(0.0)))) {
        e *= material_texture(m, 2u, tri_uv(tri, bary)).rgb;
    }
    return e;
}

// Picks an emissive triangle by power (binary search in the CDF).
uint pick_light(float u) {
    uint lo = 0u;
    uint hi = params.settings.z - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (lights[mid].cdf <= u) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    uvec2 size = params.size_frame.xy;
    if (any(greaterThanEqual(pixel, size))) {
        return;
    }
    uint index = pixel.y * size.x + pixel.x;
    uint sample_index = params.size_frame.z;
    uint seed = params.size_frame.w;
    uint max_bounces = params.settings.x;
    uint rr_depth = params.settings.y;

    vec4 jitter = rand4(pixel, sample_index, 0u, seed);
    vec2 ndc = vec2(2.0 * (float(pixel.x) + jitter.x) / float(size.x) - 1.0,
                    1.0 - 2.0 * (float(pixel.y) + jitter.y) / float(size.y));
    vec3 origin = params.cam_origin.xyz;
    vec3 dir = normalize(params.cam_forward.xyz + ndc.x * params.cam_right.xyz + ndc.y * params.cam_up.xyz);

    vec3 radiance = vec3(0.0);
    vec3 throughput = vec3(1.0);
    float prev_pdf = 0.0;  // solid-angle pdf of the BSDF sample that made this ray; 0 for the camera
    vec4 albedo = vec4(params.env.rgb, 0.0);
    vec4 normal_depth = vec4(0.0, 0.0, 0.0, BVH_INF);

    for (uint depth = 0u;; ++depth) {
        Hit hit;
        if (!bvh_closest(origin, dir, 0.0, BVH_INF, hit)) {
            if (HAS_ENV_MAP) {
                float w = 1.0;
                if (params.env_info.z != 0u && prev_pdf > 0.0) {
                    w = mis_weight(prev_pdf, env_pdf(dir, params.env_info.xy));
                }
                radiance += throughput * env_radiance(dir, params.env_info.xy) * params.env.rgb * w;
            } else {
                radiance += throughput * params.env.rgb;
            }
            break;
        }
        uint tri = hit.tri;
        vec3 ng = tri_normal(tri);
        float area = 0.5 * length(ng);
        ng = normalize(ng);
        vec3 wo = -dir;
        vec3 p = origin + hit.t * dir;

        // Emission, weighted against the light-sampling strategy that could have found it.
        vec4 uv = tri_uv(tri, hit.bary);
        vec3 le = emitted(tri, hit.bary, ng, wo);
        if (any(greaterThan(le, vec3(0.0)))) {
            float w = 1.0;
            if (HAS_LIGHTS && prev_pdf > 0.0) {
                float light_pdf = triangles[tri].light_pmf / area * hit.t * hit.t / abs(dot(ng, wo));
                w = mis_weight(prev_pdf, light_pdf);
            }
            radiance += throughput * le * w;
        }

        // Shading frame: interpolated normal, on the same side as the viewer.
        if (dot(ng, wo) < 0.0) {
            ng = -ng;
        }
        uint i0 = triangles[tri].v0;
        uint i1 = triangles[tri].v1;
        uint i2 = triangles[tri].v2;
        float b0 = 1.0 - hit.bary.x - hit.bary.y;
        vec3 n = b0 * vertices[i0].normal_u.xyz + hit.bary.x * vertices[i1].normal_u.xyz
            + hit.bary.y * vertices[i2].normal_u.xyz;
        float n_len = length(n);
        n = (n_len > 0.0 && !isnan(n_len) && !isinf(n_len)) ? n / n_len : ng;
        if (dot(n, ng) < 0.0) {
            n = -n;
        }
        // Normal map: tangent-space normal (scaled in xy) through the interpolated TBN.
        uint material = triangles[tri].material;
        if (HAS_TEXTURES) {
            if (materials[material].textures.w != 0u) {
                vec4 ta = vertices[i0].tangent;
                vec4 tb = vertices[i1].tangent;
                vec4 tc = vertices[i2].tangent;
                vec4 tg = b0 * ta + hit.bary.x * tb + hit.bary.y * tc;
                vec3 tt = tg.xyz - n * dot(n, tg.xyz);
                float tl = length(tt);
                if (tl > 1e-8) {
                    tt /= tl;
                    vec3 bt = cross(n, tt) * (ta.w < 0.0 ? -1.0 : 1.0);
                    vec3 nm = material_texture(material, 3u, uv).rgb * 2.0 - 1.0;
                    nm.xy *= materials[material].tex_transform[7].w;
                    vec3 mapped = normalize(nm.x * tt + nm.y * bt + nm.z * n);
                    if (!any(isnan(mapped)) && dot(mapped, ng) > 0.0) {
                        n = mapped;
                    }
                }
            }
        }
        vec3 t;
        vec3 b;
        basis(n, t, b);
        vec3 wo_local = vec3(dot(wo, t), dot(wo, b), dot(wo, n));
        Surface s = material_surface(material, uv);
        if (depth == 0u) {
            albedo = vec4(s.base, 1.0);
            normal_depth = vec4(n, hit.t);
        }
        if (depth >= max_bounces || wo_local.z <= 0.0) {
            break;
        }

        // Next-event estimation: one emissive triangle by power, a uniform point on it.
        if (HAS_LIGHTS && params.settings.z > 0u) {
            vec4 u = rand4(pixel, sample_index, depth * 8u + 1u, seed);
            uint k = pick_light(u.x);
            uint ltri = lights[k].tri;
            vec2 lb = sample_triangle(u.yz);
            vec3 lp = (1.0 - lb.x - lb.y) * tri_vertex(ltri, 0u) + lb.x * tri_vertex(ltri, 1u)
                + lb.y * tri_vertex(ltri, 2u);
            vec3 ln = normalize(tri_normal(ltri));
            vec3 to_light = lp - p;
            float dist2 = dot(to_light, to_light);
            vec3 wi = to_light * inversesqrt(dist2);
            vec3 l_emit = emitted(ltri, lb, ln, -wi);
            float cos_l = abs(dot(ln, wi));
            vec3 wi_local;
            if (any(greaterThan(l_emit, vec3(0.0))) && cos_l > 0.0
                && light_reaches(p, ng, t, b, n, wi, true, lp, wi_local)) {
                float light_pdf = lights[k].pmf / lights[k].area * dist2 / cos_l;
                vec3 f = bsdf_eval(s, wo_local, wi_local);
                float w = mis_weight(light_pdf, bsdf_pdf(s, wo_local, wi_local));
                radiance += throughput * f * wi_local.z * l_emit * (w / light_pdf);
            }
        }

        // Punctual lights: delta distributions, so light sampling is the only strategy (no MIS).
        // KHR_lights_punctual: intensity / d^2 with the recommended range window and a smooth
        // spot falloff.
        if (HAS_PUNCTUAL) {
            for (uint k = 0u; k < params.settings.w; ++k) {
                vec4 pr = punctual[k].position_range;
                vec4 dk = punctual[k].direction_kind;
                vec3 wi;
                float attenuation = 1.0;
                if (dk.w == LIGHT_DIRECTIONAL) {
                    wi = -dk.xyz;
                } else {
                    vec3 to_light = pr.xyz - p;
                    float dist = length(to_light);
                    wi = to_light / dist;
                    attenuation = 1.0 / (dist * dist);
                    if (pr.w > 0.0) {
                        float r = dist / pr.w;
                        attenuation *= clamp(1.0 - r * r * r * r, 0.0, 1.0) * clamp(1.0 - r * r * r * r, 0.0, 1.0);
                    }
                    if (dk.w == LIGHT_SPOT) {
                        vec4 cone = punctual[k].cone;
                        float spot = clamp((dot(-wi, dk.xyz) - cone.x) * cone.y, 0.0, 1.0);
                        attenuation *= spot * spot;
                    }
                }
                vec3 wi_local;
                if (attenuation > 0.0
                    && light_reaches(p, ng, t, b, n, wi, dk.w != LIGHT_DIRECTIONAL, pr.xyz, wi_local)) {
                    radiance += throughput * bsdf_eval(s, wo_local, wi_local) * wi_local.z
                        * punctual[k].intensity.rgb * attenuation;
                }
            }
        }

        // The environment map, importance-sampled by luminance x sin(theta), weighted by MIS.
        if (HAS_ENV_MAP && params.env_info.z != 0u) {
            vec4 u = rand4(pixel, sample_index, depth * 8u + 3u, seed);
            float pdf;
            vec3 wi = env_sample(u, params.env_info.xy, pdf);
            vec3 wi_local;
            if (pdf > 0.0 && light_reaches(p, ng, t, b, n, wi, false, wi, wi_local)) {
                vec3 f = bsdf_eval(s, wo_local, wi_local);
                float w = mis_weight(pdf, bsdf_pdf(s, wo_local, wi_local));
                vec3 le = env_radiance(wi, params.env_info.xy) * params.env.rgb;
                radiance += throughput * f * wi_local.z * le * (w / pdf);
            }
        }

        // Continue the path by sampling the BSDF.
        vec4 u = rand4(pixel, sample_index, depth * 8u + 2u, seed);
        vec3 wi_local;
        vec3 weight;
        float pdf;
        if (!bsdf_sample(s, wo_local, u.xyz, wi_local, weight, pdf)) {
            break;
        }
        vec3 wi = wi_local.x * t + wi_local.y * b + wi_local.z * n;
        if (dot(wi, ng) <= 0.0) {
            break;  // the shading normal let the sample through the geometry
        }
        throughput *= weight;
        prev_pdf = pdf;
        if (depth + 1u >= rr_depth) {
            float q = clamp(max3(throughput), 0.05, 1.0);
            if (u.w >= q) {
                break;
            }
            throughput /= q;
        }
        origin = offset_ray(p, ng);
        dir = wi;
    }

    if (any(isnan(radiance)) || any(isinf(radiance))) {
        atomicAdd(stats.nonfinite_samples, 1u);
        radiance = vec3(0.0);
    }
    float n_samples = float(sample_index + 1u);
    vec4 mean = sample_index == 0u ? vec4(0.0) : accum[index];
    vec4 m2 = sample_index == 0u ? vec4(0.0) : moment[index];
    accum[index] = vec4(mean.rgb + (radiance - mean.rgb) / n_samples, n_samples);
    moment[index] = vec4(m2.rgb + (radiance * radiance - m2.rgb) / n_samples, 0.0);
    if (sample_index == 0u) {
        aov_albedo[index] = albedo;
        aov_normal_depth[index] = normal_depth;
    }
}
