// Textures from one storage texel buffer of linear RGBA16 texels (no bindless on lavapipe; sRGB
// textures decoded at upload, so filtering is in linear space): glTF wrap modes,
// nearest or bilinear filtering, and mip chains (stored after
// level 0 where the sampler asks for them). texture_sample reads level 0: the path tracer's pixel
// jitter integrates the footprint. texture_sample_lod filters for a level of detail, for kernels
// that take one sample per pixel (the G-buffer's ray cones).
//
// The including kernel declares, before including this file:
//   layout(rgba32ui) uniform readonly uimageBuffer texture_texels;  // GpuTextures, 2 texels each
//   layout(rg32ui) uniform readonly uimageBuffer scene_texels;  // the sRGB table (256 f32 bits
//                                                               // in .x), then linear RGBA16
//                                                               // texels (sRGB decoded at upload)
// (a storage texel buffer, as the BVH's: see bvh.glsl)
#ifndef UMBRA_TEXTURE_GLSL
#define UMBRA_TEXTURE_GLSL

// Entry i of the sRGB decoding table at the head of scene_texels (vertex colours).
float srgb_table(uint i) { return uintBitsToFloat(imageLoad(scene_texels, int(i)).x); }

// GpuTexture `tex`: (offset, width, height, flags), then (levels, ...).
uvec4 texture_info(uint tex) { return imageLoad(texture_texels, int(2u * tex)); }
uint texture_levels(uint tex) { return imageLoad(texture_texels, int(2u * tex + 1u)).x; }

// i modulo n (n > 0), in [0, n), without integer division: CPU devices divide integers one lane
// at a time, and the two `%` of ((i % n) + n) % n were half the G-buffer's time on the
// textured scene (lavapipe). Exact for every int: the float quotient of the first step is within
// a few ulps, so its remainder is within a few hundred of [0, n) and exact as a float; the second
// step's quotient of that is exact but at most one off, which the selects fix.
int texture_mod(int i, int n) {
    float fn = float(n);
    int m = i - n * int(floor(float(i) / fn));
    m -= n * int(floor(float(m) / fn));
    m += m < 0 ? n : 0;
    return m >= n ? m - n : m;
}

int texture_wrap(int i, int size, bool clamp_mode, bool mirror) {
    if (clamp_mode) {
        return clamp(i, 0, size - 1);
    }
    if (mirror) {
        int period = 2 * size;
        int m = texture_mod(i, period);
        return m < size ? m : period - 1 - m;
    }
    return texture_mod(i, size);
}

// Texel (x, y), wrapped, of the w × h level that starts at texel `offset` of a texture with
// `flags` (texture_info(tex).w: read once per lookup by the callers, as the info of every
// lookup's texture is; CPU devices load a texel buffer per lane, and nothing merges the loads).
vec4 texture_texel_at(uint flags, uint offset, int w, int h, int x, int y) {
    x = texture_wrap(x, w, (flags & TEXTURE_WRAP_S_CLAMP) != 0u, (flags & TEXTURE_WRAP_S_MIRROR) != 0u);
    y = texture_wrap(y, h, (flags & TEXTURE_WRAP_T_CLAMP) != 0u, (flags & TEXTURE_WRAP_T_MIRROR) != 0u);
    uvec2 bits = imageLoad(scene_texels, int(offset + uint(y * w + x))).xy;
    return vec4(unpackUnorm2x16(bits.x), unpackUnorm2x16(bits.y));
}

vec4 texture_texel(uint tex, int x, int y) {
    uvec4 info = texture_info(tex);
    return texture_texel_at(info.w, info.x, int(info.y), int(info.z), x, y);
}

// One level (w × h texels from `offset`) of a texture with `flags` at uv: bilinear when
// `linear`, else the nearest texel, which is the bilinear blend with weights 0 on the first
// texel (exactly that texel: mix(a, b, 0) is a). One path for both: a SIMD CPU (llvmpipe) runs
// both sides of an `if` for every lane, which read five texels per lookup where this reads four.
vec4 texture_filter(uint flags, uint offset, int w, int h, vec2 uv, bool linear) {
    vec2 size = vec2(float(w), float(h));
    vec2 st = uv * size - (linear ? 0.5 : 0.0);
    vec2 f = linear ? fract(st) : vec2(0.0);
    ivec2 p = ivec2(floor(st));
    vec4 a = mix(texture_texel_at(flags, offset, w, h, p.x, p.y), texture_texel_at(flags, offset, w, h, p.x + 1, p.y),
                 f.x);
    vec4 b = mix(texture_texel_at(flags, offset, w, h, p.x, p.y + 1),
                 texture_texel_at(flags, offset, w, h, p.x + 1, p.y + 1), f.x);
    return mix(a, b, f.y);
}

// Linear RGBA of texture `tex` at uv (v down, as glTF): level 0, magnification filter.
vec4 texture_sample(uint tex, vec2 uv) {
    uvec4 info = texture_info(tex);
    return texture_filter(info.w, info.x, int(info.y), int(info.z), uv, (info.w & TEXTURE_LINEAR) != 0u);
}

// Where mip level `level` of the texture with `info` (texture_info) starts in the texel buffer,
// and its size.
void texture_level(uvec4 info, uint level, out uint offset, out int w, out int h) {
    offset = info.x;
    w = int(info.y);
    h = int(info.z);
    for (uint k = 0u; k < level; ++k) {
        offset += uint(w * h);
        w = max(w / 2, 1);
        h = max(h / 2, 1);
    }
}

// Mip level `level` of texture `tex` at uv, with the minification filter.
vec4 texture_sample_level(uint tex, uint level, vec2 uv) {
    uvec4 info = texture_info(tex);
    uint offset;
    int w, h;
    texture_level(info, level, offset, w, h);
    return texture_filter(info.w, offset, w, h, uv, (info.w & TEXTURE_MIN_LINEAR) != 0u);
}

// Linear RGBA of texture `tex` at uv for level of detail `lod` (log2 of texels per pixel
// footprint): lod <= 0 (magnified, or NaN) is texture_sample; minified, the sampler's minification
// filter on level 0 when the texture has no mips, on the nearest level (*_MIPMAP_NEAREST), or
// linearly between the two nearest levels (*_MIPMAP_LINEAR: trilinear with a linear filter).
vec4 texture_sample_lod(uint tex, vec2 uv, float lod) {
    // One code path for magnified and minified lanes (they share SIMD lanes on CPU devices, where
    // separate paths would both run): level l0 with the filter for its side of lod 0, and for
    // *_MIPMAP_LINEAR a second, coarser level only where the blend needs it.
    uvec4 info = texture_info(tex);
    uint flags = info.w;
    bool minified = lod > 0.0;
    uint top = texture_levels(tex) - 1u;
    float l = minified ? min(lod, float(top)) : 0.0;
    bool mip_linear = (flags & TEXTURE_MIP_LINEAR) != 0u;
    uint l0 = mip_linear ? uint(l) : min(uint(l + 0.5), top);
    bool linear = (flags & (minified ? TEXTURE_MIN_LINEAR : TEXTURE_LINEAR)) != 0u;
    uint offset;
    int w, h;
    texture_level(info, l0, offset, w, h);
    vec4 a = texture_filter(flags, offset, w, h, uv, linear);
    float f = l - float(l0);
    if (!mip_linear || l0 == top || !(f > 0.0)) {
        return a;
    }
    // The next level follows this one.
    vec4 b = texture_filter(flags, offset + uint(w * h), max(w / 2, 1), max(h / 2, 1), uv, linear);
    return mix(a, b, f);
}

#endif
