// The G-buffer's encoding (src/passes/gbuffer.rs documents the images): octahedral unit vectors
// and position reconstruction from view-space depth.
#ifndef UMBRA_GBUFFER_GLSL
#define UMBRA_GBUFFER_GLSL

#include "camera.glsl"
#include "sampling.glsl"

// Octahedral encoding of a unit vector into [-1, 1]^2 (Cigolle et al. 2014, "A Survey of
// Efficient Representations for Independent Unit Vectors").
vec2 oct_encode(vec3 n) {
    vec2 p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if (n.z < 0.0) {
        p = (1.0 - abs(p.yx)) * vec2(p.x >= 0.0 ? 1.0 : -1.0, p.y >= 0.0 ? 1.0 : -1.0);
    }
    return p;
}

vec3 oct_decode(vec2 e) {
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    float t = max(-n.z, 0.0);
    n.x += n.x >= 0.0 ? -t : t;
    n.y += n.y >= 0.0 ? -t : t;
    return normalize(n);
}

// The G-buffer's `layers` image (src/passes/gbuffer.rs): the layer textures' texels
// (shading.glsl's LayerTexels: `specular` in x, `layers` in y), four unorm8 values a word (exact
// for an 8-bit linear texel read unfiltered, within 1/510 otherwise), the clear coat's unit
// normal (world), octahedral, in z, and KHR_materials_anisotropy in w: the direction's angle in
// the shading frame (basis(n)'s t and b) and the strength, unorm16 each (within 5e-5 of a turn
// and of the strength).
uvec4 gbuffer_pack_layers(vec4 specular, vec4 layers, vec3 coat_n, float anisotropy, vec2 aniso_dir) {
    float turn = atan(aniso_dir.y, aniso_dir.x) * (0.5 / PI) + 0.5;
    return uvec4(packUnorm4x8(specular), packUnorm4x8(layers), packSnorm2x16(oct_encode(coat_n)),
                 packUnorm2x16(vec2(turn, anisotropy)));
}

void gbuffer_unpack_layers(uvec4 bits, out vec4 specular, out vec4 layers, out vec3 coat_n, out float anisotropy,
                           out vec2 aniso_dir) {
    specular = unpackUnorm4x8(bits.x);
    layers = unpackUnorm4x8(bits.y);
    coat_n = oct_decode(unpackSnorm2x16(bits.z));
    vec2 a = unpackUnorm2x16(bits.w);
    float angle = (a.x - 0.5) * (2.0 * PI);
    anisotropy = a.y;
    aniso_dir = vec2(cos(angle), sin(angle));
}

// The world-space point at view-space `depth` (along forward) on pixel `pixel`'s centre ray.
vec3 gbuffer_position(vec3 origin, vec3 forward, vec3 right, vec3 up, ivec2 pixel, uvec2 size, float depth) {
    vec3 dir = camera_ray(forward, right, up, vec2(pixel) + 0.5, size);
    return origin + dir * (depth / dot(dir, forward));
}

#endif
