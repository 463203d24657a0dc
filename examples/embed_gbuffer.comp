#version 460
// The example host engine's own G-buffer kernel (examples/embed.rs): a brute-force ray cast of the
// host's triangle list, written in the formats umbra's deferred passes read
// (src/passes/gbuffer.rs). A real engine would rasterize; what matters is that umbra never sees
// how the G-buffer was made. The encoding helpers come from umbra's documented gbuffer.glsl.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8) in;

// The host's own data: world-space triangles (material index in a.w's bits) and materials.
struct HostTri {
    vec4 a;
    vec4 b;
    vec4 c;
};
struct HostMaterial {
    vec4 base_metallic;       // linear base colour, metallic
    vec4 emission_roughness;  // emitted radiance, perceptual roughness
    uvec4 flags;              // x: 1 = double-sided
};

layout(set = 0, binding = 0, std430) readonly buffer Tris { HostTri tris[]; };
layout(set = 0, binding = 1, std430) readonly buffer Materials { HostMaterial materials[]; };
layout(set = 0, binding = 2, r32f) uniform writeonly image2D gb_depth;
layout(set = 0, binding = 3, rgba16f) uniform writeonly image2D gb_normal;
layout(set = 0, binding = 4, rgba16f) uniform writeonly image2D gb_base;
layout(set = 0, binding = 5, rgba16f) uniform writeonly image2D gb_emission;
layout(set = 0, binding = 6, rgba32ui) uniform writeonly uimage2D gb_material;
layout(push_constant) uniform Push {
    vec4 origin;
    vec4 forward;
    vec4 right;  // scaled by tan(yfov / 2) * aspect (orthographic: half the view's width)
    vec4 up;     // scaled by tan(yfov / 2) (orthographic: half the view's height)
    uvec4 size;  // width, height, triangle count, orthographic (0/1)
} cam;

#include "gbuffer.glsl"

const uint NO_SURFACE = 0xffffffffu;

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(pixel), cam.size.xy))) {
        return;
    }
    vec3 o;
    vec3 d;
    camera_ray(cam.origin.xyz, cam.forward.xyz, cam.right.xyz, cam.up.xyz, cam.size.w != 0u, vec2(pixel) + 0.5,
               cam.size.xy, o, d);

    // Möller–Trumbore against every triangle; the nearest hit wins.
    float best = 1e30;
    uint hit = NO_SURFACE;
    for (uint i = 0u; i < cam.size.z; ++i) {
        vec3 e1 = tris[i].b.xyz - tris[i].a.xyz;
        vec3 e2 = tris[i].c.xyz - tris[i].a.xyz;
        vec3 p = cross(d, e2);
        float det = dot(e1, p);
        if (abs(det) < 1e-12) {
            continue;
        }
        float inv = 1.0 / det;
        vec3 s = o - tris[i].a.xyz;
        float u = dot(s, p) * inv;
        vec3 q = cross(s, e1);
        float v = dot(d, q) * inv;
        float t = dot(e2, q) * inv;
        if (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 && t < best) {
            best = t;
            hit = i;
        }
    }
    if (hit == NO_SURFACE) {
        imageStore(gb_depth, pixel, vec4(0.0));
        imageStore(gb_normal, pixel, vec4(0.0));
        imageStore(gb_base, pixel, vec4(0.0));
        imageStore(gb_emission, pixel, vec4(0.0));
        imageStore(gb_material, pixel, uvec4(NO_SURFACE, 0u, 0u, 0u));
        return;
    }
    uint m = floatBitsToUint(tris[hit].a.w);
    vec3 n = normalize(cross(tris[hit].b.xyz - tris[hit].a.xyz, tris[hit].c.xyz - tris[hit].a.xyz));
    bool front = dot(n, -d) > 0.0;
    vec3 emission = front || materials[m].flags.x != 0u ? materials[m].emission_roughness.rgb : vec3(0.0);
    n = front ? n : -n;  // the G-buffer's normals face the camera's side
    imageStore(gb_depth, pixel, vec4(best * dot(d, cam.forward.xyz)));
    imageStore(gb_normal, pixel, vec4(n, materials[m].emission_roughness.w));
    imageStore(gb_base, pixel, materials[m].base_metallic);
    // Alpha: the material's ambient occlusion, 1 without an occlusion map (umbra's contract).
    imageStore(gb_emission, pixel, vec4(min(emission, vec3(65504.0)), 1.0));
    imageStore(gb_material, pixel, uvec4(m, packSnorm2x16(oct_encode(n)), 0u, 0u));
}
