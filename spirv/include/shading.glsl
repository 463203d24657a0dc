// Shading a hit of the scene: the triangle's attributes, its material as a BSDF `Surface`, its
// shading frame (interpolated and normal-mapped normal), emission, light selection, punctual-light
// incidence and shadow rays. Shared by every kernel that shades the scene (pathtrace.comp,
// gbuffer.comp, deferred.comp), so all of umbra's methods see the same surface.
//
// The including kernel reads the whole scene (`scene: full` in src/gpu/interface.rs): its
// generated kernel/<name>.glsl declares the scene's bindings and HAS_* constants. It declares
// `const bool BECKMANN` and `const bool GGX_WALTER` unless they are among its specialization
// constants. This file includes bvh.glsl, bsdf.glsl and texture.glsl.
#ifndef UMBRA_SHADING_GLSL
#define UMBRA_SHADING_GLSL

#define UMBRA_ALPHA_TEST
#include "random.glsl"
#include "bvh.glsl"
#include "bsdf.glsl"
#include "texture.glsl"

// Texel k of material `id` (MATERIAL_TEXELS per GpuMaterial; a member's first texel is
// MATERIAL_<MEMBER>_TEXEL, both generated from its layout), as floats or as unsigned integers.
vec4 material_vec(uint id, uint k) {
    return uintBitsToFloat(imageLoad(material_texels, int(MATERIAL_TEXELS * id + k)));
}

uvec4 material_uvec(uint id, uint k) {
    return imageLoad(material_texels, int(MATERIAL_TEXELS * id + k));
}

// Whether material `id` has `flag` (MATERIAL_DOUBLE_SIDED, MATERIAL_VOLUME, MATERIAL_UNLIT).
// The sheen's albedo table: SHEEN_TABLE_TEXELS texels after the last material (uploaded only for
// a scene with a sheen, so read only under HAS_SHEEN).
vec4 sheen_table_texel(uint t) {
    int first = imageSize(material_texels) - int(SHEEN_TABLE_TEXELS);
    return uintBitsToFloat(imageLoad(material_texels, first + int(t)));
}

bool material_flag(uint id, uint flag) {
    return (material_uvec(id, MATERIAL_FLAGS_TEXEL).x & flag) != 0u;
}

// Whether material `id` is unlit (KHR_materials_unlit); false in kernels not specialised for it.
bool material_unlit(uint id) {
    if (HAS_UNLIT) {
        return material_flag(id, MATERIAL_UNLIT);
    }
    return false;
}

// The volume's attenuation coefficient rgb per unit length (KHR_materials_volume; 0 without one).
vec3 material_attenuation(uint id) {
    return uintBitsToFloat(material_uvec(id, MATERIAL_FLAGS_TEXEL).yzw);
}

// KHR_materials_dispersion: the dispersion (20 / Abbe number) of material `id`, 0 unless it is a
// transmitting volume that disperses and the kernel is specialised for it (HAS_DISPERSION).
float material_dispersion(uint id) {
    if (HAS_DISPERSION) {
        return material_vec(id, MATERIAL_VOLUME_TEXEL).y;
    }
    return 0.0;
}

// The index of refraction of colour channel `c` (0 red, 1 green, 2 blue) of a volume of index
// `ior` and dispersion `dispersion`: the extension's Cauchy fit n(lambda) = max(ior + (ior - 1)
// dispersion / 20 (523655 / lambda^2 - 1.5168), 1) at the Fraunhofer line of the channel (C
// 656.3 nm, d 587.6 nm, F 486.1 nm; scene::DISPERSION_WAVELENGTHS).
float dispersed_ior(float ior, float dispersion, uint c) {
    const float lambda[3] = float[3](656.3, 587.6, 486.1);
    float l = lambda[c];
    return max(ior + (ior - 1.0) * dispersion * 0.05 * (523655.0 / (l * l) - 1.5168), 1.0);
}

// Material `id`'s texture in `slot` (MATERIAL_SLOT_*): its index + 1, 0 when the slot is empty.
uint material_slot_texture(uint id, uint slot) {
    return material_uvec(id, MATERIAL_TEXTURES_TEXEL + slot / 4u)[slot % 4u];
}

// Row `row` (0 or 1) of the texture transform of `slot` (GpuMaterial::tex_transform).
vec4 material_slot_row(uint id, uint slot, uint row) {
    return material_vec(id, MATERIAL_TEX_TRANSFORM_TEXEL + 2u * slot + row);
}

// An emissive-triangle table entry (GpuLightTri: tri, cdf, pmf, area) and a punctual light's
// vec4 k (GpuLight: position_range, direction_kind, intensity, cone), read as texels.
uint light_tri(uint k) { return imageLoad(light_texels, int(k)).x; }
vec3 light_cdf_pmf_area(uint k) { return uintBitsToFloat(imageLoad(light_texels, int(k)).yzw); }
vec4 punctual_vec(uint k, uint field) { return uintBitsToFloat(imageLoad(punctual_texels, int(4u * k + field))); }

// The scene's triangles and vertices, read as texels (on llvmpipe a texel read is a branch-free
// gather, a storage-buffer read a loop over the lanes): a GpuTriangle is two RGBA32UI texels,
// a GpuVertex three (float bits).
uvec3 tri_indices(uint tri) {
    return imageLoad(triangle_texels, int(2u * tri)).xyz;
}

uint tri_material(uint tri) {
    return imageLoad(triangle_texels, int(2u * tri)).w;
}

float tri_light_pmf(uint tri) {
    return uintBitsToFloat(imageLoad(triangle_texels, int(2u * tri + 1u)).x);
}

vec4 vertex_normal_u(uint i) {
    return uintBitsToFloat(imageLoad(vertex_texels, int(3u * i)));
}

vec4 vertex_v_uv1(uint i) {
    return uintBitsToFloat(imageLoad(vertex_texels, int(3u * i + 1u)));
}

vec4 vertex_tangent(uint i) {
    return uintBitsToFloat(imageLoad(vertex_texels, int(3u * i + 2u)));
}

// Whether the height field of the hit parallax_occlusion last marched lets light arriving along
// wi reach the point it found (true where there was none); defined below.
bool parallax_lit(vec3 wi);

// Which side of the surface light arriving along wi (unit, towards the light) comes from: 1 above
// both the shading frame (t, b, n) and the geometric surface ng, -1 below both on a surface that
// `transmits`, 0 otherwise (it cannot light the surface). Also gives wi in the frame. In kernels
// specialised for parallax (HAS_PARALLAX), light from above that the hit's height field occludes
// (parallax_lit) cannot light it either: the self-shadowing of every light sample and shadow ray.
float light_side(vec3 ng, vec3 t, vec3 b, vec3 n, bool transmits, vec3 wi, out vec3 wi_local) {
    wi_local = vec3(dot(wi, t), dot(wi, b), dot(wi, n));
    bool above = wi_local.z > 0.0 && dot(wi, ng) > 0.0;
    if (HAS_PARALLAX) {
        above = above && parallax_lit(wi);
    }
    bool below = transmits && wi_local.z < 0.0 && dot(wi, ng) < 0.0;
    return above ? 1.0 : (below ? -1.0 : 0.0);
}

// Whether light arriving along wi reaches p: from a side that can light it (light_side) and
// nothing on the shadow ray, which leaves from wi's side, and ends just short of `target` when
// `to_point` and is unbounded otherwise. Also gives wi in the frame.
bool light_reaches(vec3 p, vec3 ng, vec3 t, vec3 b, vec3 n, bool transmits, vec3 wi, bool to_point, vec3 target,
                   out vec3 wi_local) {
    float side = light_side(ng, t, b, n, transmits, wi, wi_local);
    if (side == 0.0) {
        return false;
    }
    vec3 o = offset_ray(p, side * ng);
    // One walk whether to_point or not (a CPU device would run both walks of a select).
    return !bvh_any(o, to_point ? target - o : wi, 0.0, to_point ? 0.9999 : BVH_INF);
}

// Whether the kernel is specialised for textures in `slot` (some material of the scene has one
// there): with `slot` a constant, the driver folds this and drops an unused slot's lookup, which a
// CPU device would otherwise run for every lane whatever the material.
bool slot_textured(uint slot) {
    // Spec constants only as plain `if` conditions: `!HAS_TEXTURES`, `&&` or `?:` on one would be
    // an OpSpecConstantOp, which naga rejects.
    bool textured = false;
    if (HAS_BASE_COLOR_MAP) {
        textured = textured || slot == MATERIAL_SLOT_BASE_COLOR;
    }
    if (HAS_METAL_ROUGH_MAP) {
        textured = textured || slot == MATERIAL_SLOT_METALLIC_ROUGHNESS;
    }
    if (HAS_EMISSIVE_MAP) {
        textured = textured || slot == MATERIAL_SLOT_EMISSIVE;
    }
    if (HAS_NORMAL_MAP) {
        textured = textured || slot == MATERIAL_SLOT_NORMAL;
    }
    if (HAS_OCCLUSION_MAP) {
        textured = textured || slot == MATERIAL_SLOT_OCCLUSION;
    }
    if (HAS_PARALLAX) {
        textured = textured || slot == MATERIAL_SLOT_HEIGHT;
    }
    if (HAS_SPECULAR_MAP) {
        textured = textured || slot == MATERIAL_SLOT_SPECULAR || slot == MATERIAL_SLOT_SPECULAR_COLOR;
    }
    if (HAS_TRANSMISSION_MAP) {
        textured = textured || slot == MATERIAL_SLOT_TRANSMISSION;
    }
    if (HAS_CLEARCOAT_MAP) {
        textured = textured || slot == MATERIAL_SLOT_CLEARCOAT || slot == MATERIAL_SLOT_CLEARCOAT_ROUGHNESS
            || slot == MATERIAL_SLOT_CLEARCOAT_NORMAL;
    }
    if (HAS_IRIDESCENCE_MAP) {
        textured = textured || slot == MATERIAL_SLOT_IRIDESCENCE || slot == MATERIAL_SLOT_IRIDESCENCE_THICKNESS;
    }
    if (HAS_ANISOTROPY_MAP) {
        textured = textured || slot == MATERIAL_SLOT_ANISOTROPY;
    }
    if (HAS_SHEEN_MAP) {
        textured = textured || slot == MATERIAL_SLOT_SHEEN_COLOR || slot == MATERIAL_SLOT_SHEEN_ROUGHNESS;
    }
    if (HAS_DIFFUSE_TRANSMISSION_MAP) {
        textured = textured || slot == MATERIAL_SLOT_DIFFUSE_TRANSMISSION
            || slot == MATERIAL_SLOT_DIFFUSE_TRANSMISSION_COLOR;
    }
    if (HAS_THICKNESS_MAP) {
        textured = textured || slot == MATERIAL_SLOT_THICKNESS;
    }
    return textured;
}

// Material `id`'s texture in `slot` (its index + 1, 0 when the slot is empty) and the slot's
// transformed UV from the hit's UV sets (uv.xy = uv0, uv.zw = uv1).
uint material_texture_uv(uint id, uint slot, vec4 uv, out vec2 t) {
    uint tex = 0u;
    if (slot_textured(slot)) {
        tex = material_slot_texture(id, slot);
    }
    t = vec2(0.0);
    if (tex != 0u) {
        vec4 r0 = material_slot_row(id, slot, 0u);
        vec4 r1 = material_slot_row(id, slot, 1u);
        vec2 st = r0.w != 0.0 ? uv.zw : uv.xy;
        t = vec2(dot(r0.xyz, vec3(st, 1.0)), dot(r1.xyz, vec3(st, 1.0)));
    }
    return tex;
}

// Material texture `slot` (MATERIAL_SLOT_*) at the hit's UV sets (uv.xy = uv0, uv.zw = uv1),
// level 0; white when the slot is empty.
vec4 material_texture(uint id, uint slot, vec4 uv) {
    vec2 t;
    uint tex = material_texture_uv(id, slot, uv, t);
    if (tex == 0u) {
        return vec4(1.0);
    }
    return texture_sample(tex - 1u, t);
}

// Level of detail that makes material_texture_lod read level 0, as material_texture does.
const vec2 LOD_LEVEL0 = vec2(-1e30);

// material_texture filtered for a ray cone: `cone_lod` from ray_cone_lod (LOD_LEVEL0: level 0).
vec4 material_texture_lod(uint id, uint slot, vec4 uv, vec2 cone_lod) {
    vec2 t;
    uint tex = material_texture_uv(id, slot, uv, t);
    if (tex == 0u) {
        return vec4(1.0);
    }
    tex -= 1u;
    if (max(cone_lod.x, cone_lod.y) <= LOD_LEVEL0.x) {
        return texture_sample(tex, t);
    }
    vec4 r0 = material_slot_row(id, slot, 0u);
    vec4 r1 = material_slot_row(id, slot, 1u);
    uvec4 info = texture_info(tex);
    float texel_area = float(info.y) * float(info.z) * abs(r0.x * r1.y - r0.y * r1.x);
    float lod = (r0.w != 0.0 ? cone_lod.y : cone_lod.x) + 0.5 * log2(texel_area);
    return texture_sample_lod(tex, t, lod);
}

// The texels of a hit's layer textures, which multiply the extensions' factors: specular.rgb
// KHR_materials_specular's colour (specularColorTexture, RGB), specular.a its strength
// (specularTexture, A), layers.x KHR_materials_transmission's (transmissionTexture, R), layers.y
// KHR_materials_clearcoat's weight (clearcoatTexture, R), layers.z its roughness
// (clearcoatRoughnessTexture, G); layers.w KHR_materials_volume's thickness (thicknessTexture,
// G); iridescence.x KHR_materials_iridescence's
// weight (iridescenceTexture, R), iridescence.y its film's thickness between the minimum and the
// maximum (iridescenceThicknessTexture, G); iridescence.zw unused (1); sheen.rgb
// KHR_materials_sheen's colour (sheenColorTexture, RGB), sheen.a its roughness
// (sheenRoughnessTexture, A); diffuse_transmission.rgb KHR_materials_diffuse_transmission's
// colour (diffuseTransmissionColorTexture, RGB), diffuse_transmission.a its share
// (diffuseTransmissionTexture, A). 1 where a material has no texture in the slot, and in kernels
// not specialised for the slot's group (HAS_SPECULAR_MAP, HAS_TRANSMISSION_MAP,
// HAS_CLEARCOAT_MAP, HAS_IRIDESCENCE_MAP, HAS_SHEEN_MAP, HAS_DIFFUSE_TRANSMISSION_MAP). The
// hybrid's G-buffer stores them (gb_layers; the sheen's and the diffuse transmission's in
// gb_layers2) for the lighting passes.
struct LayerTexels {
    vec4 specular;
    vec4 layers;
    vec4 iridescence;
    vec4 sheen;
    vec4 diffuse_transmission;
};

// No layer textures: every texel 1.
LayerTexels layer_texels_none() {
    LayerTexels t;
    t.specular = vec4(1.0);
    t.layers = vec4(1.0);
    t.iridescence = vec4(1.0);
    t.sheen = vec4(1.0);
    t.diffuse_transmission = vec4(1.0);
    return t;
}

// Material `id`'s layer textures at the hit's UV sets, filtered for a ray cone's `cone_lod` (see
// material_texture_lod; LOD_LEVEL0 for level 0).
LayerTexels material_layer_texels_lod(uint id, vec4 uv, vec2 cone_lod) {
    LayerTexels t = layer_texels_none();
    if (HAS_SPECULAR_MAP) {
        t.specular.rgb = material_texture_lod(id, MATERIAL_SLOT_SPECULAR_COLOR, uv, cone_lod).rgb;
        t.specular.a = material_texture_lod(id, MATERIAL_SLOT_SPECULAR, uv, cone_lod).a;
    }
    if (HAS_TRANSMISSION_MAP) {
        t.layers.x = material_texture_lod(id, MATERIAL_SLOT_TRANSMISSION, uv, cone_lod).r;
    }
    if (HAS_CLEARCOAT_MAP) {
        t.layers.y = material_texture_lod(id, MATERIAL_SLOT_CLEARCOAT, uv, cone_lod).r;
        t.layers.z = material_texture_lod(id, MATERIAL_SLOT_CLEARCOAT_ROUGHNESS, uv, cone_lod).g;
    }
    if (HAS_THICKNESS_MAP) {
        t.layers.w = material_texture_lod(id, MATERIAL_SLOT_THICKNESS, uv, cone_lod).g;
    }
    if (HAS_IRIDESCENCE_MAP) {
        t.iridescence.x = material_texture_lod(id, MATERIAL_SLOT_IRIDESCENCE, uv, cone_lod).r;
        t.iridescence.y = material_texture_lod(id, MATERIAL_SLOT_IRIDESCENCE_THICKNESS, uv, cone_lod).g;
    }
    if (HAS_SHEEN_MAP) {
        t.sheen.rgb = material_texture_lod(id, MATERIAL_SLOT_SHEEN_COLOR, uv, cone_lod).rgb;
        t.sheen.a = material_texture_lod(id, MATERIAL_SLOT_SHEEN_ROUGHNESS, uv, cone_lod).a;
    }
    if (HAS_DIFFUSE_TRANSMISSION_MAP) {
        t.diffuse_transmission.rgb =
            material_texture_lod(id, MATERIAL_SLOT_DIFFUSE_TRANSMISSION_COLOR, uv, cone_lod).rgb;
        t.diffuse_transmission.a = material_texture_lod(id, MATERIAL_SLOT_DIFFUSE_TRANSMISSION, uv, cone_lod).a;
    }
    return t;
}

// Whether the kernel is specialised for the sheen's or the diffuse transmission's textures (the
// G-buffer's gb_layers2 is written and read only then; the slots are filled only for a material
// with the layer, so a scene with them has it).
bool layers2_textured() {
    bool textured = false;
    if (HAS_SHEEN_MAP) {
        textured = true;
    }
    if (HAS_DIFFUSE_TRANSMISSION_MAP) {
        textured = true;
    }
    return textured;
}

// Whether the kernel is specialised for some layer texture but the sheen's (the G-buffer's
// gb_layers is written and read only then).
bool layer_textured() {
    bool textured = false;
    if (HAS_SPECULAR_MAP) {
        textured = true;
    }
    if (HAS_TRANSMISSION_MAP) {
        textured = true;
    }
    if (HAS_CLEARCOAT_MAP) {
        textured = true;
    }
    if (HAS_IRIDESCENCE_MAP) {
        textured = true;
    }
    if (HAS_THICKNESS_MAP) {
        textured = true;
    }
    return textured;
}

// Whether a clear coat's normal can differ from the shading normal (KHR_materials_clearcoat: the
// coat lies on the interpolated normal, tilted only by its own normal map): in kernels specialised
// for coats and for normal maps or the coat's textures. Elsewhere Surface::coat_n is the constant
// (0, 0, 1) and the coat's frame folds away.
bool coat_normal_differs() {
    bool differs = false;
    if (HAS_CLEARCOAT) {
        if (HAS_NORMAL_MAP) {
            differs = true;
        }
        if (HAS_CLEARCOAT_MAP) {
            differs = true;
        }
    }
    return differs;
}

// Whether the G-buffer's gb_layers image is written (and read): layer textures, a coat normal or
// anisotropy.
bool gbuffer_has_layers() {
    bool anisotropic = false;
    if (HAS_ANISOTROPY) {
        anisotropic = true;
    }
    return layer_textured() || coat_normal_differs() || anisotropic;
}

// Material `id` as a BSDF surface, given its (textured) base colour, metallic and roughness and
// the texels of its layer textures (material_layer_texels_lod): the dielectric specular terms
// come from the material's ior and KHR_materials_specular factors times their texels.
Surface material_surface_from(uint id, vec3 base, float metallic, float roughness, LayerTexels tex) {
    // Member by member: a whole-struct copy from a buffer is OpCopyLogical, which naga rejects.
    Surface s;
    s.base = base;
    s.metallic = metallic;
    s.alpha = max(roughness * roughness, ALPHA_MIN);
    float ior = material_vec(id, MATERIAL_PARAMS_TEXEL).y;
    float f0 = (ior - 1.0) / (ior + 1.0);
    vec4 specular = material_vec(id, MATERIAL_SPECULAR_TEXEL);
    if (HAS_SPECULAR_MAP) {
        specular *= tex.specular;
    }
    s.f0 = min(vec3(f0 * f0) * specular.rgb, vec3(1.0)) * specular.w;
    s.f90 = specular.w;
    // Transmission only where the kernel is specialised for it (HAS_TRANSMISSION); a refracting
    // boundary's eta depends on the side the ray arrives from, so the caller sets it.
    s.transmission = 0.0;
    s.eta = 1.0;
    s.thin = true;
    // The clear coat only where the kernel is specialised for it (HAS_CLEARCOAT).
    s.coat = 0.0;
    s.coat_alpha = 1.0;
    // The coat's normal in the shading frame: the shading normal until the caller sets it
    // (surface_coat_normal).
    s.coat_n = vec3(0.0, 0.0, 1.0);
    if (HAS_CLEARCOAT) {
        vec4 coat = material_vec(id, MATERIAL_CLEARCOAT_TEXEL);
        if (HAS_CLEARCOAT_MAP) {
            coat.xy *= tex.layers.yz;
        }
        s.coat = clamp(coat.x, 0.0, 1.0);
        s.coat_alpha = max(coat.y * coat.y, ALPHA_MIN);
    }
    // The sheen only where the kernel is specialised for it (HAS_SHEEN).
    s.sheen = vec3(0.0);
    s.sheen_roughness = 1.0;
    // Anisotropy only where the kernel is specialised for it and the caller gives the tangent
    // frame (surface_anisotropy).
    s.anisotropy = 0.0;
    s.aniso_dir = vec2(1.0, 0.0);
    if (HAS_SHEEN) {
        vec4 sheen = material_vec(id, MATERIAL_SHEEN_TEXEL);
        if (HAS_SHEEN_MAP) {
            sheen *= tex.sheen;
        }
        s.sheen = clamp(sheen.rgb, 0.0, 1.0);
        s.sheen_roughness = clamp(sheen.w, SHEEN_ROUGHNESS_MIN, 1.0);
    }
    // The thin film only where the kernel is specialised for it (HAS_IRIDESCENCE): its weight
    // (factor x texel), its ior, and its thickness from the minimum to the maximum by the
    // thickness texel (1, the maximum, without a texture). A film of no thickness is none.
    s.iridescence = 0.0;
    s.iridescence_ior = 1.3;
    s.iridescence_thickness = 0.0;
    if (HAS_IRIDESCENCE) {
        vec4 film = material_vec(id, MATERIAL_IRIDESCENCE_TEXEL);
        float weight = film.x;
        float thickness = 1.0;
        if (HAS_IRIDESCENCE_MAP) {
            weight *= tex.iridescence.x;
            thickness = tex.iridescence.y;
        }
        s.iridescence_thickness = mix(film.z, film.w, thickness);
        s.iridescence = s.iridescence_thickness > 0.0 ? clamp(weight, 0.0, 1.0) : 0.0;
        s.iridescence_ior = film.y;
    }
    // KHR_materials_diffuse_transmission only where the kernel is specialised for it.
    s.diffuse_transmission = 0.0;
    s.diffuse_transmission_color = vec3(1.0);
    if (HAS_DIFFUSE_TRANSMISSION) {
        vec4 through = material_vec(id, MATERIAL_DIFFUSE_TRANSMISSION_TEXEL);
        if (HAS_DIFFUSE_TRANSMISSION_MAP) {
            through *= tex.diffuse_transmission;
        }
        s.diffuse_transmission = clamp(through.w, 0.0, 1.0);
        s.diffuse_transmission_color = clamp(through.rgb, 0.0, 1.0);
    }
    // The volume's thickness (the hybrid's attenuation) only where the kernel is specialised for
    // transmission.
    s.thickness = 0.0;
    if (HAS_TRANSMISSION) {
        s.thickness = material_vec(id, MATERIAL_VOLUME_TEXEL).x;
        if (HAS_THICKNESS_MAP) {
            s.thickness *= tex.layers.w;
        }
        float transmission = material_vec(id, MATERIAL_PARAMS_TEXEL).z;
        if (HAS_TRANSMISSION_MAP) {
            transmission *= tex.layers.x;
        }
        s.transmission = clamp(transmission, 0.0, 1.0);
        // A boundary between equal indices (ior 1) bends nothing: every microfacet refracts wo
        // straight on, so Walter et al.'s refraction half vector is 0/0 there (NaN weights). It
        // transmits as thin-walled glass does (straight through where smooth); the volume's
        // attenuation still applies (it keys on MATERIAL_VOLUME, not on `thin`).
        s.thin = !material_flag(id, MATERIAL_VOLUME) || ior == 1.0;
    }
    return s;
}

// Material `id` at the hit's UV sets, textures applied, filtered for a ray cone's `cone_lod`
// (see material_texture_lod).
Surface material_surface_lod(uint id, vec4 uv, vec2 cone_lod) {
    vec3 base = material_vec(id, MATERIAL_BASE_COLOR_TEXEL).rgb * material_texture_lod(id, MATERIAL_SLOT_BASE_COLOR, uv, cone_lod).rgb;
    vec4 mr = material_texture_lod(id, MATERIAL_SLOT_METALLIC_ROUGHNESS, uv, cone_lod);
    float metallic = clamp(material_vec(id, MATERIAL_PARAMS_TEXEL).x * mr.b, 0.0, 1.0);
    float roughness = clamp(material_vec(id, MATERIAL_EMISSIVE_ROUGH_TEXEL).w * mr.g, 0.0, 1.0);
    return material_surface_from(id, base, metallic, roughness, material_layer_texels_lod(id, uv, cone_lod));
}

// Material `id`'s ambient occlusion at the hit's UV sets (glTF occlusionTexture: 1 + strength
// (r - 1); 1 without one), filtered for a ray cone's `cone_lod` (see material_texture_lod). It
// scales only image-based (ambient) light, and only in the hybrid renderer (gbuffer.comp stores
// it): the path tracer traces occlusion itself.
float material_occlusion_lod(uint id, vec4 uv, vec2 cone_lod) {
    float r = material_texture_lod(id, MATERIAL_SLOT_OCCLUSION, uv, cone_lod).r;
    float strength = material_slot_row(id, MATERIAL_SLOT_OCCLUSION, 1u).w;
    return 1.0 + strength * (r - 1.0);
}

// Material `id` at the hit's UV sets, textures applied (level 0).
Surface material_surface(uint id, vec4 uv) {
    vec3 base = material_vec(id, MATERIAL_BASE_COLOR_TEXEL).rgb * material_texture(id, MATERIAL_SLOT_BASE_COLOR, uv).rgb;
    vec4 mr = material_texture(id, MATERIAL_SLOT_METALLIC_ROUGHNESS, uv);
    float metallic = clamp(material_vec(id, MATERIAL_PARAMS_TEXEL).x * mr.b, 0.0, 1.0);
    float roughness = clamp(material_vec(id, MATERIAL_EMISSIVE_ROUGH_TEXEL).w * mr.g, 0.0, 1.0);
    return material_surface_from(id, base, metallic, roughness, material_layer_texels_lod(id, uv, LOD_LEVEL0));
}

vec3 tri_vertex(uint tri, uint k) {
    return bvh_tri_v(tri, k).xyz;
}

// Unnormalised geometric normal (length = 2 * area), by the winding.
vec3 tri_normal(uint tri) {
    vec3 a = bvh_tri_v(tri, 0u).xyz;
    return cross(bvh_tri_v(tri, 1u).xyz - a, bvh_tri_v(tri, 2u).xyz - a);
}

// A hit's geometric normal: a triangle's unnormalised one (length = 2 * area, tri_normal), an
// implicit shape's unit gradient (its Hit carries it, octahedrally encoded in `bary`).
vec3 hit_normal(Hit hit) {
    if (bvh_is_implicit(hit.tri)) {
        return oct_decode(hit.bary);
    }
    return tri_normal(hit.tri);
}

// Both UV sets at barycentrics (b1, b2) of triangle `tri`: uv0 in xy, uv1 in zw (0 on an implicit
// shape, which has no UVs).
vec4 tri_uv(uint tri, vec2 bary) {
    vec4 uv = vec4(0.0);
    if (HAS_TEXTURES) {
        if (bvh_is_implicit(tri)) {
            return uv;
        }
        uvec3 idx = tri_indices(tri);
        uint i0 = idx.x;
        uint i1 = idx.y;
        uint i2 = idx.z;
        vec4 a = vec4(vertex_normal_u(i0).w, vertex_v_uv1(i0).xyz);
        vec4 b = vec4(vertex_normal_u(i1).w, vertex_v_uv1(i1).xyz);
        vec4 c = vec4(vertex_normal_u(i2).w, vertex_v_uv1(i2).xyz);
        uv = (1.0 - bary.x - bary.y) * a + bary.x * b + bary.y * c;
    }
    return uv;
}

// COLOR_0 at barycentrics (b1, b2) of triangle `tri`, linear RGBA (opaque white in kernels not
// specialised for vertex colours, HAS_COLORS); the vertex keeps it as sRGB-encoded RGBA8, decoded
// through the sRGB table at the start of scene_texels (texture.glsl).
vec4 vertex_color(uint i) {
    uint bits = floatBitsToUint(vertex_v_uv1(i).w);
    vec4 c = unpackUnorm4x8(bits);
    c.rgb = vec3(srgb_table(bits & 255u), srgb_table((bits >> 8) & 255u), srgb_table((bits >> 16) & 255u));
    return c;
}

vec4 tri_color(uint tri, vec2 bary) {
    vec4 c = vec4(1.0);
    if (HAS_COLORS) {
        if (bvh_is_implicit(tri)) {
            return c;
        }
        uvec3 idx = tri_indices(tri);
        c = (1.0 - bary.x - bary.y) * vertex_color(idx.x) + bary.x * vertex_color(idx.y) + bary.y * vertex_color(idx.z);
    }
    return c;
}

// UV set 1 at barycentrics (b1, b2) of triangle `tri`, whether or not the kernel reads textures
// (the lightmaps' set).
vec2 tri_uv1(uint tri, vec2 bary) {
    if (bvh_is_implicit(tri)) {
        return vec2(0.0);
    }
    uvec3 idx = tri_indices(tri);
    vec2 a = vertex_v_uv1(idx.x).yz;
    vec2 b = vertex_v_uv1(idx.y).yz;
    vec2 c = vertex_v_uv1(idx.z).yz;
    return (1.0 - bary.x - bary.y) * a + bary.x * b + bary.y * c;
}

// The texture-independent part of a ray cone's level of detail at a hit of triangle `tri`
// (Akenine-Möller et al., "Texture Level of Detail Strategies for Real-Time Ray Tracing", Ray
// Tracing Gems ch. 20), for UV set 0 in x and set 1 in y: log2(width / |ng·dir|) for a cone of
// `width` at the hit, unit ray direction `dir` and unit geometric normal ng, plus
// 0.5 log2(UV area / world area) of the triangle. material_texture_lod adds each texture's
// 0.5 log2(texel count) and its transform's scale. A triangle without UV area gives -inf: level 0.
vec2 ray_cone_lod(uint tri, float width, vec3 dir, vec3 ng) {
    if (bvh_is_implicit(tri)) {
        return LOD_LEVEL0;
    }
    uvec3 idx = tri_indices(tri);
    uint i0 = idx.x;
    uint i1 = idx.y;
    uint i2 = idx.z;
    vec4 a = vec4(vertex_normal_u(i0).w, vertex_v_uv1(i0).xyz);
    vec4 e1 = vec4(vertex_normal_u(i1).w, vertex_v_uv1(i1).xyz) - a;
    vec4 e2 = vec4(vertex_normal_u(i2).w, vertex_v_uv1(i2).xyz) - a;
    // Both areas doubled: the factor cancels in the ratio.
    vec2 uv_area = abs(vec2(e1.x * e2.y - e1.y * e2.x, e1.z * e2.w - e1.w * e2.z));
    float world_area = length(tri_normal(tri));
    return log2(width / abs(dot(ng, dir))) + 0.5 * log2(uv_area / world_area);
}

// Radiance the triangle emits at barycentrics `bary` towards a viewer on the side of `towards`
// (unit normal n), emissive texture filtered for a ray cone's `cone_lod` (see material_texture_lod).
vec3 emitted_lod(uint tri, vec2 bary, vec3 n, vec3 towards, vec2 cone_lod) {
    uint m = tri_material(tri);
    bool front = dot(n, towards) > 0.0;
    bool two_sided = material_flag(m, MATERIAL_DOUBLE_SIDED);
    if (!(front || two_sided)) {
        return vec3(0.0);
    }
    vec3 e = material_vec(m, MATERIAL_EMISSIVE_ROUGH_TEXEL).rgb;
    if (HAS_EMISSIVE_MAP && any(greaterThan(e, vec3(0.0)))) {
        e *= material_texture_lod(m, MATERIAL_SLOT_EMISSIVE, tri_uv(tri, bary), cone_lod).rgb;
    }
    if (HAS_CLEARCOAT) {
        // The coat lies over the emission (KHR_materials_clearcoat): dimmed by its weight (its
        // texture's too; at `n`, not the coat's own normal).
        float coat = material_vec(m, MATERIAL_CLEARCOAT_TEXEL).x;
        if (HAS_CLEARCOAT_MAP && coat > 0.0) {
            coat *= material_texture_lod(m, MATERIAL_SLOT_CLEARCOAT, tri_uv(tri, bary), cone_lod).r;
        }
        coat = clamp(coat, 0.0, 1.0);
        e *= 1.0 - coat_weight_at(coat, abs(dot(n, normalize(towards))));
    }
    return e;
}

// Radiance the triangle emits at barycentrics `bary` towards a viewer on the side of `towards`
// (unit normal n), emissive texture at level 0.
vec3 emitted(uint tri, vec2 bary, vec3 n, vec3 towards) {
    return emitted_lod(tri, bary, n, towards, LOD_LEVEL0);
}

// Picks one of `count` emissive triangles by power (binary search in the CDF).
uint pick_light(float u, uint count) {
    uint lo = 0u;
    uint hi = count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (light_cdf_pmf_area(mid).x <= u) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}


// Parallax occlusion mapping (a material's UMBRA_implicit `parallax`, docs/gltf.md "Parallax occlusion
// mapping"; kernels specialised for it, HAS_PARALLAX). The height map (MATERIAL_SLOT_HEIGHT, R,
// level 0 with the texture's sampler) places a height field under each triangle: where it reads h
// the surface lies (1 - h) * scale world units below the triangle's plane, along its geometric
// normal on the viewer's side. parallax_occlusion marches the view ray into that field in the
// triangle's plane (`layers` equal depth steps, then `refinement` bisection steps) and moves the
// hit's barycentrics (their affine extension) to the point found, so every attribute of the hit
// (both UV sets, so every texture; vertex colours, normals) is read there. The hit's position and
// its geometric normal stay the triangle's: shadow rays and bounces leave from the triangle, and
// the silhouette stays flat. It records the point for parallax_tilt (the shading normal from the
// field's gradient) and parallax_lit (self-shadowing: light that the field occludes).

// The point parallax_occlusion found, while `parallax_active`.
bool parallax_active = false;
uint parallax_material = 0u;
vec4 parallax_uv = vec4(0.0);     // both UV sets at the point found
float parallax_depth = 0.0;       // its depth below the triangle, in units of `scale`
vec3 parallax_ng = vec3(0.0);     // the triangle's unit normal on the viewer's side
vec3 parallax_a = vec3(0.0);      // world in-plane offset d -> barycentric offset (d.a, d.b)
vec3 parallax_b = vec3(0.0);
vec4 parallax_duv1 = vec4(0.0);   // both UV sets' change per unit of barycentric b1, b2
vec4 parallax_duv2 = vec4(0.0);

// The height field at UV sets `uv`: R of the height map (1: the triangle's surface).
float parallax_height(uint material, vec4 uv) {
    return material_texture(material, MATERIAL_SLOT_HEIGHT, uv).r;
}

// Both UV sets' change for an in-plane world offset d.
vec4 parallax_uv_offset(vec3 d) {
    return dot(d, parallax_a) * parallax_duv1 + dot(d, parallax_b) * parallax_duv2;
}

// Marches the height field of triangle `tri`'s material, if it has one, from the hit at
// barycentrics `bary` seen along wo (unit, towards the viewer); returns the barycentrics of the
// point found (`bary` itself without a height map, and in kernels not specialised for parallax).
// Sets the state parallax_tilt and parallax_lit read; call it at every hit before either.
vec2 parallax_occlusion(uint tri, vec2 bary, vec3 wo) {
    parallax_active = false;
    if (HAS_PARALLAX) {
        if (bvh_is_implicit(tri)) {
            return bary;
        }
        uint material = tri_material(tri);
        if (material_slot_texture(material, MATERIAL_SLOT_HEIGHT) == 0u) {
            return bary;
        }
        vec3 a = tri_vertex(tri, 0u);
        vec3 e1 = tri_vertex(tri, 1u) - a;
        vec3 e2 = tri_vertex(tri, 2u) - a;
        vec3 ng = cross(e1, e2);
        float g11 = dot(e1, e1);
        float g12 = dot(e1, e2);
        float g22 = dot(e2, e2);
        float det = g11 * g22 - g12 * g12;
        if (!(det > 0.0)) {
            return bary;
        }
        ng = normalize(ng);
        float cos_o = dot(wo, ng);
        if (cos_o < 0.0) {
            ng = -ng;
            cos_o = -cos_o;
        }
        parallax_a = (g22 * e1 - g12 * e2) / det;
        parallax_b = (g11 * e2 - g12 * e1) / det;
        uvec3 idx = tri_indices(tri);
        vec4 u0 = vec4(vertex_normal_u(idx.x).w, vertex_v_uv1(idx.x).xyz);
        parallax_duv1 = vec4(vertex_normal_u(idx.y).w, vertex_v_uv1(idx.y).xyz) - u0;
        parallax_duv2 = vec4(vertex_normal_u(idx.z).w, vertex_v_uv1(idx.z).xyz) - u0;
        vec4 uv = u0 + bary.x * parallax_duv1 + bary.y * parallax_duv2;

        vec4 prm = material_vec(material, MATERIAL_PARALLAX_TEXEL);
        float scale = prm.x;
        uint layers = uint(prm.y);
        uint refinement = uint(prm.z);
        // The view ray's in-plane world offset per unit of depth below the plane (long towards
        // grazing: cos_o is kept from 0, where the ray never descends).
        vec3 lateral = -(wo - cos_o * ng) / max(cos_o, 1e-6);
        vec3 step_world = scale * lateral;  // per unit of depth fraction s (depth s * scale)
        vec4 step_uv = parallax_uv_offset(step_world);
        // Linear search: the first layer s_i = i / layers at or below the field (1 - h <= s_i);
        // s = 1 always is (h >= 0).
        float above = 0.0;
        float below = 0.0;
        for (uint i = 0u; i <= layers; ++i) {
            below = float(i) / float(layers);
            if (below >= 1.0 - parallax_height(material, uv + below * step_uv)) {
                break;
            }
            above = below;
        }
        // Bisection between the last layer above the field and the first at or below it.
        if (below > 0.0) {
            for (uint k = 0u; k < refinement; ++k) {
                float mid = 0.5 * (above + below);
                if (mid >= 1.0 - parallax_height(material, uv + mid * step_uv)) {
                    below = mid;
                } else {
                    above = mid;
                }
            }
        }
        parallax_active = true;
        parallax_material = material;
        parallax_uv = uv + below * step_uv;
        parallax_depth = below;
        parallax_ng = ng;
        return bary + below * vec2(dot(step_world, parallax_a), dot(step_world, parallax_b));
    }
    return bary;
}

// The height field's normal at the point parallax_occlusion found, around the smooth normal n:
// n - scale * grad h (the gradient in world units along the triangle's plane, central differences
// one height-map texel apart in the direction it is densest), normalised. n itself where no point
// was found.
vec3 parallax_tilt(vec3 n) {
    if (!parallax_active) {
        return n;
    }
    uint material = parallax_material;
    uint tex = material_slot_texture(material, MATERIAL_SLOT_HEIGHT) - 1u;
    uvec4 info = texture_info(tex);
    vec4 r0 = material_slot_row(material, MATERIAL_SLOT_HEIGHT, 0u);
    vec4 r1 = material_slot_row(material, MATERIAL_SLOT_HEIGHT, 1u);
    vec3 t1;
    vec3 t2;
    basis(parallax_ng, t1, t2);
    vec4 d1 = parallax_uv_offset(t1);
    vec4 d2 = parallax_uv_offset(t2);
    // Texels per world unit along t1 and t2 in the height map.
    vec2 st1 = r0.w != 0.0 ? d1.zw : d1.xy;
    vec2 st2 = r0.w != 0.0 ? d2.zw : d2.xy;
    vec2 size = vec2(float(info.y), float(info.z));
    float density1 = length(vec2(dot(r0.xy, st1), dot(r1.xy, st1)) * size);
    float density2 = length(vec2(dot(r0.xy, st2), dot(r1.xy, st2)) * size);
    float eps = 1.0 / max(max(density1, density2), 1e-6);
    float g1 = parallax_height(material, parallax_uv + eps * d1) - parallax_height(material, parallax_uv - eps * d1);
    float g2 = parallax_height(material, parallax_uv + eps * d2) - parallax_height(material, parallax_uv - eps * d2);
    float scale = material_vec(material, MATERIAL_PARALLAX_TEXEL).x;
    vec3 tilted = normalize(n - (scale / (2.0 * eps)) * (g1 * t1 + g2 * t2));
    return any(isnan(tilted)) ? n : tilted;
}

// Whether light arriving along wi (unit, towards the light) reaches the point parallax_occlusion
// found through its height field: the ray from the point towards the light, stepped up in the
// layers' depth steps, stays above the field (a hard shadow; a step less than 1e-3 of `scale`
// into the field does not count). True where no point was found and for light from below the
// triangle (light_side decides there).
bool parallax_lit(vec3 wi) {
    if (!parallax_active) {
        return true;
    }
    float cos_i = dot(wi, parallax_ng);
    if (cos_i <= 0.0) {
        return true;
    }
    uint material = parallax_material;
    vec4 prm = material_vec(material, MATERIAL_PARALLAX_TEXEL);
    float scale = prm.x;
    uint layers = uint(prm.y);
    vec4 rise_uv = parallax_uv_offset(scale * (wi - cos_i * parallax_ng) / cos_i);  // per unit of rise
    float step_ = 1.0 / float(layers);
    bool lit = true;
    for (uint j = 1u; j <= layers; ++j) {
        float rise = float(j) * step_;
        float s = parallax_depth - rise;
        if (s <= 0.0) {
            break;
        }
        if (1.0 - parallax_height(material, parallax_uv + rise * rise_uv) < s - 1e-3) {
            lit = false;
            break;
        }
    }
    return lit;
}

// The interpolated vertex normal at barycentrics `bary` of triangle `tri` (ng where it
// degenerates), flipped to ng's side, tilted by the height field where parallax_occlusion found a
// point (parallax_tilt): the shading normal before any normal map.
vec3 interpolated_normal(uint tri, vec2 bary, vec3 ng) {
    uvec3 idx = tri_indices(tri);
    float b0 = 1.0 - bary.x - bary.y;
    vec3 n = b0 * vertex_normal_u(idx.x).xyz + bary.x * vertex_normal_u(idx.y).xyz
        + bary.y * vertex_normal_u(idx.z).xyz;
    float n_len = length(n);
    n = (n_len > 0.0 && !isnan(n_len) && !isinf(n_len)) ? n / n_len : ng;
    if (dot(n, ng) < 0.0) {
        n = -n;
    }
    if (HAS_PARALLAX) {
        // The height field's normal (parallax_occlusion's point); a normal map tilts it further.
        n = parallax_tilt(n);
    }
    return n;
}

// Normal n tilted by the tangent-space normal map in texture `slot` (MATERIAL_SLOT_NORMAL or
// MATERIAL_SLOT_CLEARCOAT_NORMAL; its scale in the slot's second transform row, w) through the
// interpolated TBN, where the material has one and the result stays above the geometry; n
// otherwise.
vec3 normal_mapped(uint tri, vec2 bary, vec3 ng, vec3 n, vec4 uv, vec2 cone_lod, uint slot) {
    uint material = tri_material(tri);
    if (material_slot_texture(material, slot) != 0u) {
        uvec3 idx = tri_indices(tri);
        float b0 = 1.0 - bary.x - bary.y;
        vec4 ta = vertex_tangent(idx.x);
        vec4 tb = vertex_tangent(idx.y);
        vec4 tc = vertex_tangent(idx.z);
        vec4 tg = b0 * ta + bary.x * tb + bary.y * tc;
        vec3 tt = tg.xyz - n * dot(n, tg.xyz);
        float tl = length(tt);
        if (tl > 1e-8) {
            tt /= tl;
            vec3 bt = cross(n, tt) * (ta.w < 0.0 ? -1.0 : 1.0);
            vec3 nm = material_texture_lod(material, slot, uv, cone_lod).rgb * 2.0 - 1.0;
            nm.xy *= material_slot_row(material, slot, 1u).w;
            vec3 mapped = normalize(nm.x * tt + nm.y * bt + nm.z * n);
            if (!any(isnan(mapped)) && dot(mapped, ng) > 0.0) {
                n = mapped;
            }
        }
    }
    return n;
}


// The shading normal at barycentrics `bary` of triangle `tri` whose geometric normal `ng` faces
// the viewer: the interpolated vertex normal (ng where it degenerates), flipped to ng's side, tilted
// by the height field where parallax_occlusion found a point (parallax_tilt), then the material's
// normal map (tangent-space normal scaled in xy, through the interpolated TBN)
// where it keeps the normal above the geometry; the normal map filtered for a ray cone's `cone_lod`
// (see material_texture_lod; LOD_LEVEL0 for level 0).
vec3 shading_normal_lod(uint tri, vec2 bary, vec3 ng, vec4 uv, vec2 cone_lod) {
    // An implicit shape: the gradient is the normal (no vertex normals, no normal map).
    if (bvh_is_implicit(tri)) {
        return ng;
    }
    vec3 n = interpolated_normal(tri, bary, ng);
    if (HAS_NORMAL_MAP) {
        n = normal_mapped(tri, bary, ng, n, uv, cone_lod, MATERIAL_SLOT_NORMAL);
    }
    return n;
}

// The clear coat's normal at a hit (world, on ng's side): the interpolated normal (parallax
// included) tilted by the coat's own normal map alone (KHR_materials_clearcoat: the base's normal
// map does not reach the coat); ng on an implicit shape.
vec3 coat_normal_lod(uint tri, vec2 bary, vec3 ng, vec4 uv, vec2 cone_lod) {
    if (bvh_is_implicit(tri)) {
        return ng;
    }
    vec3 n = interpolated_normal(tri, bary, ng);
    if (HAS_CLEARCOAT_MAP) {
        n = normal_mapped(tri, bary, ng, n, uv, cone_lod, MATERIAL_SLOT_CLEARCOAT_NORMAL);
    }
    return n;
}

// Gives surface s the coat's normal `coat_n` (world) in the shading frame (t, b, n), in kernels
// where it can differ from n (coat_normal_differs).
void surface_coat_normal(inout Surface s, vec3 coat_n, vec3 t, vec3 b, vec3 n) {
    if (coat_normal_differs()) {
        s.coat_n = vec3(dot(coat_n, t), dot(coat_n, b), dot(coat_n, n));
    }
}

// KHR_materials_anisotropy at a hit of triangle `tri` (barycentrics `bary`, UV sets `uv`, the
// anisotropy texture filtered for `cone_lod`) with shading frame (t, b, n): gives surface s its
// strength and direction, in kernels specialised for it (HAS_ANISOTROPY). The direction in tangent
// space is the texture's RG as 2 rg - 1 ((1, 0) without a texture) turned by anisotropyRotation
// (counter-clockwise, from the tangent towards the bitangent); it is taken to world through the
// interpolated vertex tangent made orthogonal to n and the bitangent cross(n, t) * sign (the
// normal map's frame), the strength is anisotropyStrength times the texture's B. Where there is
// no tangent frame (tangent w 0: no TANGENT and no UVs, src/scene/geometry.rs; implicit shapes)
// or the direction is zero, s stays isotropic.
void surface_anisotropy(inout Surface s, uint tri, vec2 bary, vec4 uv, vec2 cone_lod, vec3 t, vec3 b, vec3 n) {
    if (HAS_ANISOTROPY) {
        uint material = tri_material(tri);
        vec4 aniso = material_vec(material, MATERIAL_ANISOTROPY_TEXEL);
        float strength = aniso.x;
        vec2 dir = vec2(1.0, 0.0);
        if (HAS_ANISOTROPY_MAP) {
            if (material_slot_texture(material, MATERIAL_SLOT_ANISOTROPY) != 0u) {
                vec3 texel = material_texture_lod(material, MATERIAL_SLOT_ANISOTROPY, uv, cone_lod).rgb;
                dir = texel.rg * 2.0 - 1.0;
                strength *= texel.b;
            }
        }
        dir = vec2(aniso.y * dir.x - aniso.z * dir.y, aniso.z * dir.x + aniso.y * dir.y);
        vec3 d = vec3(0.0);
        if (!bvh_is_implicit(tri)) {
            uvec3 idx = tri_indices(tri);
            float b0 = 1.0 - bary.x - bary.y;
            vec4 ta = vertex_tangent(idx.x);
            vec4 tg = b0 * ta + bary.x * vertex_tangent(idx.y) + bary.y * vertex_tangent(idx.z);
            vec3 tt = tg.xyz - n * dot(n, tg.xyz);
            float tl = length(tt);
            if (tl > 1e-8 && abs(ta.w) > 0.5) {
                tt /= tl;
                vec3 bt = cross(n, tt) * (ta.w < 0.0 ? -1.0 : 1.0);
                d = dir.x * tt + dir.y * bt;
            }
        }
        vec2 local = vec2(dot(d, t), dot(d, b));
        float len = length(local);
        if (strength > 0.0 && len > 1e-6) {
            s.anisotropy = min(strength, 1.0);
            s.aniso_dir = local / len;
        }
    }
}

// shading_normal_lod with the normal map at level 0.
vec3 shading_normal(uint tri, vec2 bary, vec3 ng, vec4 uv) {
    return shading_normal_lod(tri, bary, ng, uv, LOD_LEVEL0);
}

// Light from punctual light k at p: the unit direction towards it, whether that is a point
// (`to_point`, then at `position`) or a direction, and the radiometric factor, intensity x
// attenuation (KHR_lights_punctual: intensity / d^2 with the recommended range window and a
// smooth spot falloff). 0 when the light cannot reach p.
vec3 punctual_incident(uint k, vec3 p, out vec3 wi, out bool to_point, out vec3 position) {
    vec4 pr = punctual_vec(k, 0u);
    vec4 dk = punctual_vec(k, 1u);
    position = pr.xyz;
    to_point = dk.w != LIGHT_DIRECTIONAL;
    float attenuation = 1.0;
    if (!to_point) {
        wi = -dk.xyz;
    } else {
        vec3 to_light = pr.xyz - p;
        float dist = length(to_light);
        wi = to_light / dist;
        attenuation = 1.0 / (dist * dist);
        if (pr.w > 0.0) {
            float r = dist / pr.w;
            float window = clamp(1.0 - r * r * r * r, 0.0, 1.0);
            attenuation *= window * window;
        }
        if (dk.w == LIGHT_SPOT) {
            vec4 cone = punctual_vec(k, 3u);
            float spot = clamp((dot(-wi, dk.xyz) - cone.x) * cone.y, 0.0, 1.0);
            attenuation *= spot * spot;
        }
    }
    return punctual_vec(k, 2u).rgb * attenuation;
}

// Whether emissive_point may sample a triangle by solid angle (EmitterSampling::SolidAngle): a
// kernel that asks for it defines EMITTER_SOLID_ANGLE before including this file (the path
// tracers, from a specialization constant), the others sample by area alone. On llvmpipe the
// solid-angle code runs for every SIMD lane of every light sample once it is compiled in.
#ifndef EMITTER_SOLID_ANGLE
#define EMITTER_SOLID_ANGLE false
#endif

// The solid angle Ω of the emissive triangle with corners v0, v1, v2 (area `area`, half the length
// of cross(v1 - v0, v2 - v0)) as seen from p where emissive_point samples it by solid angle, else
// 0 (sampled by area), with the unit directions a, b, c from p to the corners: where its area
// over the squared distance to v0 (about Ω, and cheap) and Ω itself are at least SPHERICAL_MIN,
// and Ω is at most SPHERICAL_MAX. Only near triangles pay for Ω's arithmetic (three
// normalisations, an atan), and only there does solid-angle sampling lower the variance much.
float emissive_solid_angle(vec3 p, vec3 v0, vec3 v1, vec3 v2, float area, out vec3 a, out vec3 b, out vec3 c) {
    float omega = 0.0;
    a = vec3(0.0);
    b = vec3(0.0);
    c = vec3(0.0);
    // (The constant as the condition itself: its negation would be an OpSpecConstantOp, which
    // naga's SPIR-V reader rejects.)
    if (EMITTER_SOLID_ANGLE) {
        vec3 d = v0 - p;
        if (area >= SPHERICAL_MIN * dot(d, d)) {
            a = normalize(d);
            b = normalize(v1 - p);
            c = normalize(v2 - p);
            omega = spherical_triangle_area(a, b, c);
        }
    }
    return omega >= SPHERICAL_MIN && omega <= SPHERICAL_MAX ? omega : 0.0;
}

// A point on the emissive triangles as seen from p: one of `count` by power (u.x), then a point
// on it (u.yz): uniform in the solid angle it subtends at p where that is neither tiny nor near a
// hemisphere (sample_spherical_triangle; pdf pmf / Ω), else uniform on its area (pdf pmf / area
// × r² / cos at the light). Sampling by solid angle takes the light's 1/r² and cosine out of the
// estimate, which area sampling leaves in: far less variance at points near a large emitter
// (pbrt-v4's triangle sampling, without its warp by the receiver's cosine). With SAMPLE_REUSE
// (bsdf.glsl) the triangle is picked by u.y, whose share of the triangle, stretched, replaces
// u.y. True when it emits towards p; then gives the direction wi (unit, world) and the point, the
// emitted radiance and the solid-angle pdf of the sample. Visibility is the caller's
// (light_reaches to the point).
bool emissive_point(vec3 p, vec3 u, uint count, out vec3 wi, out vec3 lp, out vec3 l_emit, out float light_pdf) {
    uint k = pick_light(SAMPLE_REUSE ? u.y : u.x, count);
    vec3 cdf_pmf_area = light_cdf_pmf_area(k);
    if (SAMPLE_REUSE) {
        // The interval of u.y that picked k exactly: from the CDF, not its pmf (rounded apart).
        float lo = k > 0u ? light_cdf_pmf_area(k - 1u).x : 0.0;
        u.y = stretch(u.y, lo, cdf_pmf_area.x - lo);
    }
    uint ltri = light_tri(k);
    vec3 v0 = tri_vertex(ltri, 0u);
    vec3 v1 = tri_vertex(ltri, 1u);
    vec3 v2 = tri_vertex(ltri, 2u);
    vec3 e1 = v1 - v0;
    vec3 e2 = v2 - v0;
    vec3 ln = cross(e1, e2);
    vec3 a;
    vec3 b;
    vec3 c;
    float omega = emissive_solid_angle(p, v0, v1, v2, 0.5 * length(ln), a, b, c);
    ln = normalize(ln);
    bool spherical = omega > 0.0;
    vec2 lb = sample_triangle(u.yz);
    if (spherical) {
        // The sampled direction's barycentrics on the triangle (a ray from p along w), clamped
        // onto it against rounding.
        vec3 w = sample_spherical_triangle(a, b, c, omega, u.yz);
        vec3 s1 = cross(w, e2);
        vec3 o = p - v0;
        float inv = 1.0 / dot(s1, e1);
        lb = clamp(vec2(dot(o, s1), dot(w, cross(o, e1))) * inv, 0.0, 1.0);
        lb /= max(1.0, lb.x + lb.y);
    }
    lp = (1.0 - lb.x - lb.y) * v0 + lb.x * v1 + lb.y * v2;
    vec3 to_light = lp - p;
    float dist2 = dot(to_light, to_light);
    wi = to_light * inversesqrt(dist2);
    l_emit = emitted(ltri, lb, ln, -wi);
    float cos_l = abs(dot(ln, wi));
    light_pdf = spherical ? cdf_pmf_area.y / omega : cdf_pmf_area.y / cdf_pmf_area.z * dist2 / cos_l;
    return any(greaterThan(l_emit, vec3(0.0))) && cos_l > 0.0 && light_pdf > 0.0;
}

// Next-event estimation on the emissive triangles (emissive_point) with its shadow ray. True
// when the point emits towards p and nothing blocks it; then gives the direction in the shading
// frame, the emitted radiance and the solid-angle pdf of the sample.
bool sample_emissive(vec3 p, vec3 ng, vec3 t, vec3 b, vec3 n, bool transmits, vec3 u, uint count,
                     out vec3 wi_local, out vec3 l_emit, out float light_pdf) {
    vec3 wi;
    vec3 lp;
    return emissive_point(p, u, count, wi, lp, l_emit, light_pdf)
        && light_reaches(p, ng, t, b, n, transmits, wi, true, lp, wi_local);
}

// The solid-angle density with which sample_emissive from `origin` picks the point a ray from
// there hits at distance `dist` on emissive triangle `tri` (area `area`, half the length of
// tri_normal, as emissive_point computes it; unit normal ng), arriving from direction wo (unit,
// towards the origin): what MIS weighs emission found by BSDF sampling against. By solid angle
// or by area as emissive_point chooses from there.
float emissive_pdf(uint tri, float area, vec3 origin, float dist, vec3 ng, vec3 wo) {
    float omega = 0.0;
    // Kernels without EMITTER_SOLID_ANGLE read no corners here.
    if (EMITTER_SOLID_ANGLE) {
        vec3 a;
        vec3 b;
        vec3 c;
        omega = emissive_solid_angle(origin, tri_vertex(tri, 0u), tri_vertex(tri, 1u), tri_vertex(tri, 2u), area, a,
                                     b, c);
    }
    return omega > 0.0 ? tri_light_pmf(tri) / omega : tri_light_pmf(tri) / area * dist * dist / abs(dot(ng, wo));
}

// Whether light sampling at a surface covers the side below it too (a transmitting material, or
// a diffusely transmitting one, in a kernel specialised for it).
bool surface_transmits(Surface s) {
    bool transmits = false;
    if (HAS_TRANSMISSION) {
        transmits = s.transmission > 0.0;
    }
    if (HAS_DIFFUSE_TRANSMISSION) {
        transmits = transmits || s.diffuse_transmission > 0.0;
    }
    return transmits && s.metallic < 1.0;
}

// Whether the kernel is specialised for some transmission (KHR_materials_transmission or
// _diffuse_transmission): light can pass a surface, into a volume's medium too.
bool scene_transmits() {
    bool transmits = false;
    if (HAS_TRANSMISSION) {
        transmits = true;
    }
    if (HAS_DIFFUSE_TRANSMISSION) {
        transmits = true;
    }
    return transmits;
}

// Punctual lights evaluated at a shading point: all of them up to PUNCTUAL_ALL; beyond,
// PUNCTUAL_ALL of them picked by power (GpuLight's selection table), stratified over the table,
// each weighted by 1 / (PUNCTUAL_ALL pmf): unbiased, and the work stays bounded. (llvmpipe ends
// every loop of an invocation after 65,535 iterations in all, which one shadow ray per light cut
// short from about 13,000 lights over a plane, or a few hundred in Sponza.) PUNCTUAL_ALL: 16
// (src/gpu/interface.rs).

// The light whose selection interval holds u (binary search of the inclusive prefix).
uint pick_punctual(float u, uint count) {
    uint lo = 0u;
    uint hi = count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (punctual_vec(mid, 2u).w <= u) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

#ifdef UMBRA_SHADOW_MAPS
// Defined by a kernel that includes this file with UMBRA_SHADOW_MAPS defined: light k's
// visibility at p from its shadow map, ng facing the light's side, wi towards the light.
float punctual_shadow(uint k, vec3 p, vec3 ng, vec3 wi);
// Likewise: light k's ray-traced visibility at p as a sized light (SHADOW_SIZED), ng facing the
// light's side, wi towards its centre (at `position` when `to_point`).
float punctual_sized_shadow(uint k, vec3 p, vec3 ng, vec3 wi, bool to_point, vec3 position);
#endif

// How much of punctual light k arriving along wi reaches p (0 or 1 with shadow rays; a filtered
// fraction from a shadow map when the kernel has them, SHADOW_MAPS; the unoccluded fraction of
// rays to the light's sphere or cone for sized lights, SHADOW_SIZED); wi in the frame.
float punctual_visibility(uint k, vec3 p, vec3 ng, vec3 t, vec3 b, vec3 n, bool transmits, vec3 wi, bool to_point,
                          vec3 position, out vec3 wi_local) {
#ifdef UMBRA_SHADOW_MAPS
    if (SHADOW_MAPS) {
        float side = light_side(ng, t, b, n, transmits, wi, wi_local);
        return side == 0.0 ? 0.0 : punctual_shadow(k, p, side * ng, wi);
    }
    if (SHADOW_SIZED) {
        float side = light_side(ng, t, b, n, transmits, wi, wi_local);
        return side == 0.0 ? 0.0 : punctual_sized_shadow(k, p, side * ng, wi, to_point, position);
    }
#endif
    return light_reaches(p, ng, t, b, n, transmits, wi, to_point, position, wi_local) ? 1.0 : 0.0;
}

// The j-th of the punctual lights a shading point evaluates (j < min(count, PUNCTUAL_ALL)): light
// j itself when there are at most PUNCTUAL_ALL, else stratum j of the table by power (u places
// the strata); its weight 1 or 1 / (PUNCTUAL_ALL pmf).
uint punctual_evaluated(uint j, uint count, float u, out float weight) {
    bool every = count <= PUNCTUAL_ALL;
    uint k = every ? j : pick_punctual((float(j) + u) * (1.0 / float(PUNCTUAL_ALL)), count);
    weight = every ? 1.0 : 1.0 / (float(PUNCTUAL_ALL) * punctual_vec(k, 3u).z);
    return k;
}

// Direct light from the `count` punctual lights at p (one shadow ray per light evaluated, u
// places the strata when they are sampled): delta distributions, so light sampling is the only
// strategy; through a transmitting surface too.
vec3 punctual_direct(vec3 p, vec3 ng, vec3 t, vec3 b, vec3 n, Surface s, vec3 wo_local, uint count, float u) {
    vec3 sum = vec3(0.0);
    for (uint j = 0u; j < min(count, PUNCTUAL_ALL); ++j) {
        float weight;
        uint k = punctual_evaluated(j, count, u, weight);
        vec3 wi;
        bool to_point;
        vec3 position;
        vec3 li = punctual_incident(k, p, wi, to_point, position);
        vec3 wi_local;
        if (any(greaterThan(li, vec3(0.0)))) {
            float visible = punctual_visibility(k, p, ng, t, b, n, surface_transmits(s), wi, to_point, position, wi_local);
            if (visible > 0.0) {
                sum += weight * visible * bsdf_eval(s, wo_local, wi_local) * abs(wi_local.z) * li;
            }
        }
    }
    return sum;
}

// glTF alpha: base colour factor × base colour texture alpha at the hit. MASK: opaque from the
// cutoff up. BLEND: opaque with probability alpha (stochastic transparency), decided by a hash of
// the ray (origin and direction) and the triangle, so each ray draws afresh (jittered camera
// rays, each path vertex) and the mean over samples is the blend.
bool bvh_alpha_opaque(uint tri, vec2 bary, vec3 origin, vec3 dir) {
    uint m = tri_material(tri);
    float alpha = material_vec(m, MATERIAL_BASE_COLOR_TEXEL).a * material_texture(m, MATERIAL_SLOT_BASE_COLOR, tri_uv(tri, bary)).a
        * tri_color(tri, bary).a;
    if (floatBitsToUint(bvh_tri_v(tri, 1u).w) == 1u) {
        return alpha >= material_vec(m, MATERIAL_PARAMS_TEXEL).w;
    }
    uvec4 h = pcg4d(uvec4(floatBitsToUint(origin) ^ floatBitsToUint(dir).yzx, tri));
    return float(h.x >> 8) * (1.0 / 16777216.0) < alpha;
}

#endif
