#version 460
// The G-buffer from primary rays through the BVH, one ray through each pixel's centre: what the
// deferred passes (SSAO, lighting) need of the first surface, in the formats src/passes/gbuffer.rs
// documents. Shading attributes come from shading.glsl, so the G-buffer sees exactly the surface
// the path tracer sees.
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"
#include "pixel.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(constant_id = 0) const bool HAS_TEXTURES = false;
layout(constant_id = 1) const bool HAS_ALPHA = false;
const bool BECKMANN = false;
// The hybrid passes shade reflection only (see src/passes/deferred.rs).
const bool HAS_TRANSMISSION = false;

layout(set = 0, binding = 0, rgba32ui) uniform readonly uimageBuffer bvh_node_texels;
layout(set = 0, binding = 1, rgba32ui) uniform readonly uimageBuffer bvh_tri_texels;
layout(set = 0, binding = 2, std430) readonly buffer Triangles { GpuTriangle triangles[]; };
layout(set = 0, binding = 3, std430) readonly buffer Vertices { GpuVertex vertices[]; };
layout(set = 0, binding = 4, std430) readonly buffer Materials { GpuMaterial materials[]; };
layout(set = 0, binding = 5, std430) readonly buffer Textures { GpuTexture textures[]; };
layout(set = 0, binding = 6, r32ui) uniform readonly uimageBuffer scene_texels;
// Unused here (shading.glsl's light helpers), declared so the include compiles.
layout(set = 0, binding = 7, std430) readonly buffer Lights { GpuLightTri lights[]; };
layout(set = 0, binding = 8, std430) readonly buffer Punctual { GpuLight punctual[]; };
layout(set = 0, binding = 9, r32f) uniform writeonly image2D gb_depth;
layout(set = 0, binding = 10, rgba16f) uniform writeonly image2D gb_normal;
layout(set = 0, binding = 11, rgba16f) uniform writeonly image2D gb_base;
layout(set = 0, binding = 12, rgba16f) uniform writeonly image2D gb_emission;
layout(set = 0, binding = 13, rg32ui) uniform writeonly uimage2D gb_material;
layout(push_constant) uniform Push { GBufferParams params; };

#include "gbuffer.glsl"
#include "shading.glsl"

void main() {
    ivec2 pixel = ivec2(tile_pixel());
    uvec2 size = params.size.xy;
    if (any(greaterThanEqual(uvec2(pixel), size))) {
        return;
    }
    vec3 origin = params.cam_origin.xyz;
    vec3 forward = params.cam_forward.xyz;
    vec3 dir = camera_ray(forward, params.cam_right.xyz, params.cam_up.xyz, vec2(pixel) + 0.5, size);

    Hit hit;
    if (!bvh_closest(origin, dir, 0.0, BVH_INF, hit)) {
        imageStore(gb_depth, pixel, vec4(0.0));
        imageStore(gb_normal, pixel, vec4(0.0));
        imageStore(gb_base, pixel, vec4(0.0));
        imageStore(gb_emission, pixel, vec4(0.0));
        imageStore(gb_material, pixel, uvec4(GBUFFER_NO_SURFACE, 0u, 0u, 0u));
        return;
    }
    uint tri = hit.tri;
    vec3 ng = normalize(tri_normal(tri));
    vec3 wo = -dir;
    vec4 uv = tri_uv(tri, hit.bary);
    // One sample per pixel: textures are filtered over the pixel's footprint, a ray cone whose
    // spread is the angle of a pixel (Ray Tracing Gems ch. 20) and whose width at the hit is t
    // times that.
    vec2 cone_lod = LOD_LEVEL0;
    if (HAS_TEXTURES) {
        float spread = atan(2.0 * length(params.cam_up.xyz) / float(size.y));
        cone_lod = ray_cone_lod(tri, hit.t * spread, dir, ng);
    }
    vec3 le = emitted_lod(tri, hit.bary, ng, wo, cone_lod);
    if (dot(ng, wo) < 0.0) {
        ng = -ng;
    }
    uint material = triangles[tri].material;
    vec3 n = shading_normal_lod(tri, hit.bary, ng, uv, cone_lod);
    Surface s = material_surface_lod(material, uv, cone_lod);

    // View-space depth: distance along the camera's forward axis.
    imageStore(gb_depth, pixel, vec4(hit.t * dot(dir, forward)));
    imageStore(gb_normal, pixel, vec4(n, sqrt(s.alpha)));
    imageStore(gb_base, pixel, vec4(s.base, s.metallic));
    imageStore(gb_emission, pixel, vec4(min(le, vec3(65504.0)), 0.0));
    imageStore(gb_material, pixel, uvec4(material, packSnorm2x16(oct_encode(ng)), 0u, 0u));
}
