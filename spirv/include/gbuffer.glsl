// The G-buffer's encoding (src/passes/gbuffer.rs documents the images): octahedral unit vectors
// and position reconstruction from view-space depth.
#ifndef UMBRA_GBUFFER_GLSL
#define UMBRA_GBUFFER_GLSL

#include "camera.glsl"
#include "octahedral.glsl"
#include "sampling.glsl"

// The G-buffer's `layers` image (src/passes/gbuffer.rs): the layer textures' texels
// (shading.glsl's LayerTexels: `specular` in x, `layers` in y, four unorm8 values a word: exact
// for an 8-bit linear texel read unfiltered, within 1/510 otherwise), the clear coat's unit normal
// (world), octahedral, in z, and in w four unorm8 values: `iridescence.xy` (the film's weight and
// thickness texels, as x and y) and KHR_materials_anisotropy's direction and strength. The
// direction is an axis (the lobes and the bent normal are the same for d and -d): its angle in the
// shading frame (basis(n)'s t and b) modulo pi, within 1/512 of a half turn (0.18 degrees); the
// strength within 1/510.
uvec4 gbuffer_pack_layers(vec4 specular, vec4 layers, vec4 iridescence, vec3 coat_n, float anisotropy,
                          vec2 aniso_dir) {
    float half_turn = fract(atan(aniso_dir.y, aniso_dir.x) * (1.0 / PI) + 1.0);
    // A half turn of 1 - 1/512 and above rounds to 1 = pi: the same axis as 0.
    return uvec4(packUnorm4x8(specular), packUnorm4x8(layers), packSnorm2x16(oct_encode(coat_n)),
                 packUnorm4x8(vec4(iridescence.xy, half_turn, anisotropy)));
}

void gbuffer_unpack_layers(uvec4 bits, out vec4 specular, out vec4 layers, out vec4 iridescence, out vec3 coat_n,
                           out float anisotropy, out vec2 aniso_dir) {
    specular = unpackUnorm4x8(bits.x);
    layers = unpackUnorm4x8(bits.y);
    coat_n = oct_decode(unpackSnorm2x16(bits.z));
    vec4 w = unpackUnorm4x8(bits.w);
    iridescence = vec4(w.xy, 1.0, 1.0);
    float angle = w.z * PI;
    anisotropy = w.w;
    aniso_dir = vec2(cos(angle), sin(angle));
}

// The G-buffer's `layers2` image: KHR_materials_sheen's texels (shading.glsl's LayerTexels.sheen,
// four unorm8 values) in x, KHR_materials_diffuse_transmission's (diffuse_transmission) in y; z, w
// unused (0).
uvec4 gbuffer_pack_layers2(vec4 sheen, vec4 diffuse_transmission) {
    return uvec4(packUnorm4x8(sheen), packUnorm4x8(diffuse_transmission), 0u, 0u);
}

void gbuffer_unpack_layers2(uvec4 bits, out vec4 sheen, out vec4 diffuse_transmission) {
    sheen = unpackUnorm4x8(bits.x);
    diffuse_transmission = unpackUnorm4x8(bits.y);
}

// The world-space point at view-space `depth` (along forward) on the ray pixel `pixel` sampled:
// through its centre moved by the camera's `jitter` (camera_jitter).
vec3 gbuffer_position(vec3 eye, vec3 forward, vec3 right, vec3 up, bool orthographic, vec2 jitter, ivec2 pixel,
                      uvec2 size, float depth) {
    return camera_point(eye, forward, right, up, orthographic, vec2(pixel) + 0.5 + jitter, size, depth);
}

#endif
