// ReSTIR DI (Bitterli et al. 2020, "Spatiotemporal reservoir resampling for real-time ray
// tracing with dynamic direct lighting") for the hybrid renderer's direct light: per pixel a
// reservoir holds one light sample chosen among many candidates by resampled importance sampling
// (RIS), reused from the previous frame's reservoir (temporal) and from neighbouring pixels'
// (spatial); the lighting pass then shades that one sample with one shadow ray
// (src/passes/restir.rs documents the steps, the two combinations and where each is biased).
//
// The light samples, their target function and the reservoirs are resample.glsl's (shared with
// the path tracer's first hit); this file adds the G-buffer's shading points and the reservoirs'
// storage.
//
// The including kernel includes random.glsl, gbuffer.glsl and shading.glsl first and has the
// G-buffer bound as gb_depth, gb_normal, gb_base, gb_material, gb_layers and gb_layers2, and `params` with `camera`,
// `size`, `light_count` and `punctual_count`.
#ifndef UMBRA_RESTIR_GLSL
#define UMBRA_RESTIR_GLSL

#include "resample.glsl"

// Random-number streams of the ReSTIR steps (rand4's sample index is frame-based).
const uint RNG_RESTIR_CANDIDATE = 0u;
const uint RNG_RESTIR_TEMPORAL = 1u;
const uint RNG_RESTIR_SPATIAL = 2u;
const uint RNG_RESTIR_PICK = 3u;  // which candidate a reservoir keeps

// Pixel `pixel`'s surface from the G-buffer; false where it has none (the environment).
bool gbuffer_point(ivec2 pixel, out ShadePoint sp) {
    sp.depth = imageLoad(gb_depth, pixel).x;
    if (sp.depth <= 0.0) {
        return false;
    }
    vec3 origin;
    vec3 dir;
    camera_ray(params.camera.origin, params.camera.forward, params.camera.right, params.camera.up,
               camera_orthographic(params.camera.flags), camera_sample(pixel, params.camera.flags), params.size, origin,
               dir);
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
