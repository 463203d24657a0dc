// ReSTIR DI (Bitterli et al. 2020, "Spatiotemporal reservoir resampling for real-time ray
// tracing with dynamic direct lighting") for the hybrid renderer's direct light: per pixel a
// reservoir holds one light sample chosen among many candidates by resampled importance sampling
// (RIS), reused from the previous frame's reservoir (temporal) and from neighbouring pixels'
// (spatial); the lighting pass then shades that one sample with one shadow ray
// (src/passes/restir.rs documents the steps, the two combinations and where each is biased).
//
// The light samples: a point on an emissive triangle (its sampling-table entry and barycentrics:
// area measure) or a punctual light (counting measure). The target function p^ is the luminance
// of the unshadowed contribution f cos Le G at the shading point; the candidates come from the
// emissive table by power (a uniform point on the triangle) or the punctual lights' table by
// power, the two pools picked with probability restir_emissive_share().
//
// The including kernel includes random.glsl, gbuffer.glsl and shading.glsl first and has the
// G-buffer bound as gb_depth, gb_normal, gb_base, gb_material, gb_layers and gb_layers2, and `params` with `camera`,
// `size`, `light_count` and `punctual_count`.
#ifndef UMBRA_RESTIR_GLSL
#define UMBRA_RESTIR_GLSL

// Random-number streams of the ReSTIR steps (rand4's sample index is frame-based).
const uint RNG_RESTIR_CANDIDATE = 0u;
const uint RNG_RESTIR_TEMPORAL = 1u;
const uint RNG_RESTIR_SPATIAL = 2u;
const uint RNG_RESTIR_PICK = 3u;  // which candidate a reservoir keeps

// A G-buffer pixel as a shading point: position, view depth, frames, the material as a BSDF
// surface and the viewing direction in its frame.
struct ShadePoint {
    vec3 p;
    float depth;
    vec3 ng;  // geometric normal (the G-buffer's, facing the camera)
    vec3 n;   // shading normal
    vec3 t;
    vec3 b;
    vec3 wo;  // towards the camera (world)
    vec3 wo_local;
    uint material;
    float roughness;  // perceptual
    vec2 uv1;         // the G-buffer's second UV set (lightmaps)
    Surface s;
};

// Pixel `pixel`'s surface from the G-buffer; false where it has none (the environment).
bool gbuffer_point(ivec2 pixel, out ShadePoint sp) {
    sp.depth = imageLoad(gb_depth, pixel).x;
    if (sp.depth <= 0.0) {
        return false;
    }
    vec3 origin;
    vec3 dir;
    camera_ray(params.camera.origin, params.camera.forward, params.camera.right, params.camera.up,
               params.camera.orthographic != 0u, vec2(pixel) + 0.5, params.size, origin, dir);
    sp.p = origin + dir * (sp.depth / dot(dir, params.camera.forward));
    vec4 normal_rough = imageLoad(gb_normal, pixel);
    vec4 base_metal = imageLoad(gb_base, pixel);
    uvec4 mat = imageLoad(gb_material, pixel);
    sp.material = mat.x;
    sp.roughness = normal_rough.w;
    sp.uv1 = uintBitsToFloat(mat.zw);
    sp.n = normalize(normal_rough.xyz);
    sp.ng = oct_decode(unpackSnorm2x16(mat.y));
    sp.wo = -dir;
    basis(sp.n, sp.t, sp.b);
    sp.wo_local = vec3(dot(sp.wo, sp.t), dot(sp.wo, sp.b), dot(sp.wo, sp.n));
    // The layer textures' texels, the coat's normal and the anisotropy, where the scene has some
    // (the G-buffer leaves them unwritten otherwise).
    LayerTexels layers = layer_texels_none();
    vec3 coat_n = sp.n;
    float anisotropy = 0.0;
    vec2 aniso_dir = vec2(1.0, 0.0);
    if (gbuffer_has_layers()) {
        gbuffer_unpack_layers(imageLoad(gb_layers, pixel), layers.specular, layers.layers, layers.iridescence, coat_n,
                              anisotropy, aniso_dir);
    }
    if (layers2_textured()) {
        gbuffer_unpack_layers2(imageLoad(gb_layers2, pixel), layers.sheen, layers.diffuse_transmission);
    }
    sp.s = material_surface_from(mat.x, base_metal.rgb, base_metal.a, normal_rough.w, layers);
    surface_coat_normal(sp.s, coat_n, sp.t, sp.b, sp.n);
    if (HAS_ANISOTROPY) {
        // KHR_materials_anisotropy (the G-buffer's: in basis(n)'s frame, as sp.t and sp.b).
        sp.s.anisotropy = anisotropy;
        sp.s.aniso_dir = aniso_dir;
    }
    if (HAS_TRANSMISSION) {
        // Seen from outside (wo on the front): glass (ior) behind the surface.
        sp.s.eta = material_vec(mat.x, 3u).y;
    }
    return true;
}

// Whether direct light shades the point at all (a lit surface seen from its front).
bool gbuffer_lit(ivec2 pixel, out ShadePoint sp) {
    return gbuffer_point(pixel, sp) && !material_unlit(sp.material) && sp.wo_local.z > 0.0;
}

// The probability that a candidate comes from the emissive triangles rather than the punctual
// lights.
float restir_emissive_share() {
    bool emissive = false;
    if (HAS_LIGHTS) {
        emissive = params.light_count > 0u;
    }
    bool punctual = false;
    if (HAS_PUNCTUAL) {
        punctual = params.punctual_count > 0u;
    }
    return emissive ? (punctual ? 0.5 : 1.0) : 0.0;
}

// One candidate light sample from u: its id (GpuReservoir::light), barycentrics and source
// density (area measure for a triangle's point, a probability for a punctual light; 0: none).
uint restir_candidate(vec4 u, out vec2 bary, out float pdf) {
    float share = restir_emissive_share();
    bary = vec2(0.0);
    pdf = 0.0;
    uint id = RESTIR_NONE;
    if (HAS_LIGHTS) {
        if (u.w < share) {
            uint k = pick_light(u.x, params.light_count);
            vec3 cdf_pmf_area = light_cdf_pmf_area(k);
            bary = sample_triangle(u.yz);
            pdf = share * cdf_pmf_area.y / cdf_pmf_area.z;
            id = k;
        }
    }
    if (HAS_PUNCTUAL) {
        if (u.w >= share) {
            uint k = pick_punctual(u.x, params.punctual_count);
            pdf = (1.0 - share) * punctual_vec(k, 3u).z;
            id = RESTIR_PUNCTUAL | k;
        }
    }
    return id;
}

// Light sample (id, bary) seen from sp, unshadowed: f cos Le G (rgb; 0 where it cannot light
// the point), the direction towards it (world), and the shadow ray's end (a point, or none for a
// directional light).
vec3 restir_contribution(ShadePoint sp, uint id, vec2 bary, out vec3 wi, out bool to_point, out vec3 target) {
    vec3 li = vec3(0.0);
    wi = sp.n;
    to_point = false;
    target = sp.p;
    if (id == RESTIR_NONE) {
        return vec3(0.0);
    }
    // (A reused sample of a light the scene no longer has, after an update, lights nothing.)
    if (HAS_PUNCTUAL) {
        if ((id & RESTIR_PUNCTUAL) != 0u && (id & ~RESTIR_PUNCTUAL) < params.punctual_count) {
            li = punctual_incident(id & ~RESTIR_PUNCTUAL, sp.p, wi, to_point, target);
        }
    }
    if (HAS_LIGHTS) {
        if ((id & RESTIR_PUNCTUAL) == 0u && id < params.light_count) {
            uint ltri = light_tri(id);
            target = (1.0 - bary.x - bary.y) * tri_vertex(ltri, 0u) + bary.x * tri_vertex(ltri, 1u)
                   + bary.y * tri_vertex(ltri, 2u);
            vec3 ln = normalize(tri_normal(ltri));
            vec3 to_light = target - sp.p;
            float dist2 = dot(to_light, to_light);
            wi = to_light * inversesqrt(dist2);
            to_point = true;
            li = emitted(ltri, bary, ln, -wi) * (abs(dot(ln, wi)) / dist2);
        }
    }
    vec3 wi_local;
    if (light_side(sp.ng, sp.t, sp.b, sp.n, surface_transmits(sp.s), wi, wi_local) == 0.0) {
        return vec3(0.0);
    }
    return bsdf_eval(sp.s, sp.wo_local, wi_local) * abs(wi_local.z) * li;
}

// The target function p^ of light sample (id, bary) at sp.
float restir_target(ShadePoint sp, uint id, vec2 bary) {
    vec3 wi;
    bool to_point;
    vec3 target;
    return luminance(restir_contribution(sp, id, bary, wi, to_point, target));
}

// Whether nothing blocks the light sample's direction wi (towards `target` when to_point).
bool restir_visible(ShadePoint sp, vec3 wi, bool to_point, vec3 target) {
    vec3 wi_local;
    return light_reaches(sp.p, sp.ng, sp.t, sp.b, sp.n, surface_transmits(sp.s), wi, to_point, target, wi_local);
}

// A reservoir being built: the sample kept, the sum of the resampling weights, the candidates it
// stands for (M) and, once finished, the unbiased contribution weight W.
struct Reservoir {
    uint id;
    vec2 bary;
    float w_sum;
    float m;
    float w;
};

Reservoir reservoir_empty() {
    Reservoir r;
    r.id = RESTIR_NONE;
    r.bary = vec2(0.0);
    r.w_sum = 0.0;
    r.m = 0.0;
    r.w = 0.0;
    return r;
}

// Streams one candidate of resampling weight `weight` into r, kept with probability weight /
// the new sum (u uniform in [0, 1)); true when it was kept.
bool reservoir_add(inout Reservoir r, uint id, vec2 bary, float weight, float u) {
    if (!(weight > 0.0)) {
        return false;
    }
    r.w_sum += weight;
    if (u * r.w_sum < weight) {
        r.id = id;
        r.bary = bary;
        return true;
    }
    return false;
}

// Finishes r: W = w_sum / (z p^(y)), z the candidate count the weights are normalised by (1/M
// weights: z = M), 0 when the kept sample's target is 0.
void reservoir_finish(inout Reservoir r, float target, float z) {
    r.w = (target > 0.0 && z > 0.0) ? r.w_sum / (z * target) : 0.0;
    if (!(r.w > 0.0)) {
        r.w = 0.0;
    }
}

// Reservoir i of the GpuReservoir array `buf` into r, and r with the surface it was built for
// (sp: view depth, normal; so a later frame can tell whether it still applies) into element i,
// member by member (a whole-struct copy from a buffer is OpCopyLogical, which naga rejects), with
// `bits` for its flags (RESTIR_VISIBLE). An invalid point stores an empty reservoir.
#define RESERVOIR_LOAD(buf, i, r)          \
    {                                      \
        r.id = buf[i].light;               \
        r.bary = buf[i].bary;              \
        r.w_sum = 0.0;                     \
        r.m = buf[i].count;                \
        r.w = buf[i].weight;               \
    }
#define RESERVOIR_STORE(buf, i, r, sp, valid, bits)                                            \
    {                                                                                      \
        buf[i].light = (valid) ? r.id : RESTIR_NONE;                                       \
        buf[i].bary = r.bary;                                                              \
        buf[i].weight = (valid) ? r.w : 0.0;                                               \
        buf[i].count = (valid) ? r.m : 0.0;                                                \
        buf[i].depth = (valid) ? sp.depth : 0.0;                                           \
        buf[i].normal = packSnorm2x16(oct_encode((valid) ? sp.n : vec3(0.0, 0.0, 1.0)));  \
        buf[i].flags = bits;                                                               \
    }

// Whether a reservoir built for a surface at view depth `depth` with normal `n` may be reused
// at sp (Bitterli et al.'s heuristic: depths within 10 %, normals within about 25 degrees).
bool restir_similar(ShadePoint sp, float depth, vec3 n) {
    return abs(depth - sp.depth) <= 0.1 * sp.depth && dot(n, sp.n) >= 0.9;
}

#endif
