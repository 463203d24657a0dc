#version 460
// Shadow maps, step 4: one workgroup per tile of SHADOW_TILE² texels, one invocation per texel,
// over the large triangles in the tile's list (shadow_bin.comp, which also wrote their edge
// functions and depths). Each invocation tests its texel centre against them (shadow_raster.glsl:
// watertight edge functions, a tie rule), keeps the nearest depth, merges
// the small triangles' depth from the scratch layer (and resets it for the next layer), and
// writes its texel of the map: every texel once, by its owner, so the result does not depend on
// the lists' order. (Setting the triangles up in shared memory instead, 256 at a time behind
// barriers, measured 20 % slower on lavapipe.)
#extension GL_GOOGLE_include_directive : require
#include "kernel/shadow_raster.glsl"

layout(local_size_x = 16, local_size_y = 16) in;

const bool BECKMANN = false;
const bool GGX_WALTER = false;
#include "shading.glsl"
#include "shadow_raster.glsl"

void main() {
    uvec2 tile = gl_WorkGroupID.xy;
    uvec2 texel = tile * SHADOW_TILE + gl_LocalInvocationID.xy;
    bool mine = all(lessThan(texel, uvec2(params.size)));
    uint t = tile.y * params.tiles + tile.x;
    uint start = min(tile_start[t], params.capacity);
    uint count = min(tile_count[t], params.capacity - start);
    // Every invocation has its count: zero it for the next layer's counting pass.
    barrier();
    if (gl_LocalInvocationIndex == 0u) {
        tile_count[t] = 0u;
    }
    float nearest = BVH_INF;
    for (uint j = 0u; j < count; ++j) {
        uint tri = tile_tris[start + j];
        vec4 r0 = imageLoad(setup_texels, int(3u * tri));
        vec4 r1 = imageLoad(setup_texels, int(3u * tri + 1u));
        vec4 r2 = imageLoad(setup_texels, int(3u * tri + 2u));
        float depth;
        vec2 bary;
        if (shadow_covers(r0.xyz, r1.xyz, r2.xyz, vec3(r0.w, r1.w, r2.w), texel, depth, bary) && depth < nearest
            && shadow_opaque(tri, bary, texel)) {
            nearest = depth;
        }
    }
    if (mine) {
        uint i = texel.y * params.size + texel.x;
        nearest = min(nearest, uintBitsToFloat(shadow_scratch[i]));
        shadow_scratch[i] = floatBitsToUint(BVH_INF);
        imageStore(shadow_depth, int(params.offset + i), vec4(nearest));
    }
}
