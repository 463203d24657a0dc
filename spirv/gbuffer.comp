#version 460
// The G-buffer of the first surface through each pixel's centre: what the deferred passes (SSAO,
// lighting) need of it, in the formats src/passes/gbuffer.rs documents. Ray-cast through the BVH
// (`RASTER` false) or resolved from the visibility buffer (`RASTER` true, Burns and Hunt 2013):
// the pixel's ray meets the rasterized triangle in the traversal's own watertight terms, so its
// hit (t, barycentrics) is the ray cast's bit for bit wherever both found that triangle. Shading attributes come from shading.glsl, so the G-buffer sees exactly the surface
// the path tracer sees.
#extension GL_GOOGLE_include_directive : require
#include "kernel/gbuffer.glsl"
#include "pixel.glsl"

KERNEL_LOCAL_SIZE;

const bool BECKMANN = false;
const bool GGX_WALTER = false;
// HAS_TRANSMISSION is not specialised: the hybrid passes shade reflection only (see
// src/passes/deferred.rs).

#include "gbuffer.glsl"
#include "shading.glsl"

void main() {
    ivec2 pixel = ivec2(tile_pixel());
    uvec2 size = params.size;
    if (any(greaterThanEqual(uvec2(pixel), size))) {
        return;
    }
    vec3 forward = params.camera.forward;
    bool orthographic = camera_orthographic(params.camera.flags);
    vec3 origin;
    vec3 dir;
    camera_ray(params.camera.origin, forward, params.camera.right, params.camera.up, orthographic, camera_sample(pixel, params.camera.flags),
               size, origin, dir);

    Hit hit;
    bool found;
    if (RASTER) {
        uint tri = visibility[pixel.y * params.vis_stride + pixel.x].x;
        found = tri != RASTER_NO_TRIANGLE;
        if (found) {
            // The traversal's watertight terms for the pixel's ray, without its inside test: where
            // the ray meets the triangle, its t and barycentrics bit for bit; where the centre
            // lies within rounding of an edge that the test puts outside, the same formulas a
            // hair beyond it (no fallback to a ray cast: on llvmpipe a traversal inside an `if`
            // costs every pixel a pass of its loop).
            precise float u;
            precise float v;
            precise float w;
            precise float big_t;
            uint order;
            uint alpha;
            bvh_edge_functions(bvh_ray(origin, dir), tri, u, v, w, big_t, order, alpha);
            precise float det = u + v + w;
            hit.tri = tri;
            hit.t = big_t / det;
            hit.bary = vec2(v / det, w / det);
            // An edge-on triangle (the rasterizer's rounding against the ray's): no surface.
            found = hit.t > 0.0 && !isinf(hit.t);
        }
    } else {
        found = bvh_closest(origin, dir, 0.0, BVH_INF, hit);
    }
    if (!found) {
        imageStore(gb_depth, pixel, vec4(0.0));
        imageStore(gb_normal, pixel, vec4(0.0));
        imageStore(gb_base, pixel, vec4(0.0));
        imageStore(gb_emission, pixel, vec4(0.0));
        imageStore(gb_material, pixel, uvec4(GBUFFER_NO_SURFACE, 0u, 0u, 0u));
        if (params.motion != 0u) {
            imageStore(gb_motion, pixel, vec4(0.0));
        }
        return;
    }
    uint tri = hit.tri;
    // Where the geometry moved: the point's motion since the previous geometry, its vertices'
    // at its barycentrics (before parallax moves them: the surface moves, not its texture).
    if (params.motion != 0u) {
        vec3 motion = vec3(0.0);
        if (!bvh_is_implicit(tri)) {
            uvec3 idx = tri_indices(tri);
            motion = (1.0 - hit.bary.x - hit.bary.y) * vertex_motion[idx.x].xyz + hit.bary.x * vertex_motion[idx.y].xyz
                + hit.bary.y * vertex_motion[idx.z].xyz;
        }
        imageStore(gb_motion, pixel, vec4(motion, 0.0));
    }
    vec3 ng = normalize(hit_normal(hit));
    vec3 wo = -dir;
    // Parallax occlusion mapping: the hit's attributes are read where the view ray meets the
    // material's height field (the same function as the path tracer's; deferred.comp marches it
    // again for the self-shadowing).
    hit.bary = parallax_occlusion(tri, hit.bary, wo);
    vec4 uv = tri_uv(tri, hit.bary);
    // One sample per pixel: textures are filtered over the pixel's footprint, a ray cone whose
    // spread is the angle of a pixel (Ray Tracing Gems ch. 20) and whose width at the hit is t
    // times that; an orthographic pixel's footprint is a beam of the pixel's width.
    vec2 cone_lod = LOD_LEVEL0;
    if (HAS_TEXTURES) {
        float pixel_extent = 2.0 * length(params.camera.up) / float(size.y);
        float width = orthographic ? pixel_extent : hit.t * atan(pixel_extent);
        cone_lod = ray_cone_lod(tri, width, dir, ng);
    }
    vec3 le = emitted_lod(tri, hit.bary, ng, wo, cone_lod);
    if (dot(ng, wo) < 0.0) {
        ng = -ng;
    }
    uint material = tri_material(tri);
    vec3 n = shading_normal_lod(tri, hit.bary, ng, uv, cone_lod);
    Surface s = material_surface_lod(material, uv, cone_lod);
    s.base *= tri_color(tri, hit.bary).rgb;
    // The occlusion map, for the lighting pass's image-based (ambient) light.
    float occlusion = 1.0;
    if (HAS_OCCLUSION_MAP) {
        occlusion = material_occlusion_lod(material, uv, cone_lod);
    }

    // View-space depth: distance along the camera's forward axis.
    imageStore(gb_depth, pixel, vec4(hit.t * dot(dir, forward)));
    imageStore(gb_normal, pixel, vec4(n, sqrt(s.alpha)));
    imageStore(gb_base, pixel, vec4(s.base, s.metallic));
    imageStore(gb_emission, pixel, vec4(min(le, vec3(65504.0)), occlusion));
    imageStore(gb_material, pixel, uvec4(material, packSnorm2x16(oct_encode(ng)), floatBitsToUint(tri_uv1(tri, hit.bary))));
    // The layer textures' texels (the lighting passes multiply the factors by them), the clear
    // coat's normal and the anisotropy, only where the scene has some: the image is left
    // unwritten otherwise.
    LayerTexels layers = layer_texels_none();
    if (gbuffer_has_layers() || layers2_textured()) {
        layers = material_layer_texels_lod(material, uv, cone_lod);
    }
    if (gbuffer_has_layers()) {
        vec3 coat_n = n;
        if (coat_normal_differs()) {
            coat_n = coat_normal_lod(tri, hit.bary, ng, uv, cone_lod);
        }
        // KHR_materials_anisotropy in the frame the lighting passes rebuild (basis(n)).
        vec3 t;
        vec3 b;
        basis(n, t, b);
        surface_anisotropy(s, tri, hit.bary, uv, cone_lod, t, b, n);
        imageStore(gb_layers, pixel,
                   gbuffer_pack_layers(layers.specular, layers.layers, layers.iridescence, coat_n, s.anisotropy,
                                       s.aniso_dir));
    }
    // The sheen's and the diffuse transmission's texels, only where the scene has them.
    if (layers2_textured()) {
        imageStore(gb_layers2, pixel, gbuffer_pack_layers2(layers.sheen, layers.diffuse_transmission));
    }
}
