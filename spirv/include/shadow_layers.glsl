// The shadow maps' records in `shadow_texels` (src/passes/shadow.rs, ShadowPlan::texels): a
// layer's six texels read back as a ShadowLayer (shadow.glsl's lookups, shadow_mark.comp's marks).
#ifndef UMBRA_SHADOW_LAYERS_GLSL
#define UMBRA_SHADOW_LAYERS_GLSL

struct ShadowLayer {
    vec4 row0;
    vec4 row1;
    vec4 row2;
    vec4 row3;
    uint offset;
    uint size;
    uint kind;
    float texel_world;
    float depth_far;
    float split;
};

vec4 shadow_header(uint i) { return uintBitsToFloat(imageLoad(shadow_texels, int(i))); }

ShadowLayer shadow_layer(uint first) {
    ShadowLayer l;
    l.row0 = shadow_header(first);
    l.row1 = shadow_header(first + 1u);
    l.row2 = shadow_header(first + 2u);
    l.row3 = shadow_header(first + 3u);
    uvec4 info = imageLoad(shadow_texels, int(first + 4u));
    vec4 more = shadow_header(first + 5u);
    l.offset = info.x;
    l.size = info.y;
    l.kind = info.z;
    l.texel_world = more.x;
    l.depth_far = more.y;
    l.split = more.z;
    return l;
}

#endif
