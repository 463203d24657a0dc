// Textures from one storage buffer of RGBA8 texels (no bindless on lavapipe): glTF wrap modes,
// nearest or bilinear filtering, sRGB decoding before filtering. No mipmaps: the path tracer's
// pixel jitter integrates the footprint.
//
// The including kernel declares, before including this file:
//   readonly buffer ... { GpuTexture textures[]; };
//   readonly buffer ... { uint texels[]; };
#ifndef UMBRA_TEXTURE_GLSL
#define UMBRA_TEXTURE_GLSL

int texture_wrap(int i, int size, bool clamp_mode, bool mirror) {
    if (clamp_mode) {
        return clamp(i, 0, size - 1);
    }
    if (mirror) {
        int period = 2 * size;
        int m = ((i % period) + period) % period;
        return m < size ? m : period - 1 - m;
    }
    return ((i % size) + size) % size;
}

vec3 srgb_to_linear(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), greaterThan(c, vec3(0.04045)));
}

vec4 texture_texel(uint tex, int x, int y) {
    uint flags = textures[tex].flags;
    int w = int(textures[tex].width);
    int h = int(textures[tex].height);
    x = texture_wrap(x, w, (flags & TEXTURE_WRAP_S_CLAMP) != 0u, (flags & TEXTURE_WRAP_S_MIRROR) != 0u);
    y = texture_wrap(y, h, (flags & TEXTURE_WRAP_T_CLAMP) != 0u, (flags & TEXTURE_WRAP_T_MIRROR) != 0u);
    vec4 c = unpackUnorm4x8(texels[textures[tex].offset + uint(y * w + x)]);
    if ((flags & TEXTURE_SRGB) != 0u) {
        c.rgb = srgb_to_linear(c.rgb);
    }
    return c;
}

// Linear RGBA of texture `tex` at uv (v down, as glTF).
vec4 texture_sample(uint tex, vec2 uv) {
    vec2 size = vec2(float(textures[tex].width), float(textures[tex].height));
    if ((textures[tex].flags & TEXTURE_LINEAR) == 0u) {
        ivec2 p = ivec2(floor(uv * size));
        return texture_texel(tex, p.x, p.y);
    }
    vec2 st = uv * size - 0.5;
    vec2 f = fract(st);
    ivec2 p = ivec2(floor(st));
    vec4 a = mix(texture_texel(tex, p.x, p.y), texture_texel(tex, p.x + 1, p.y), f.x);
    vec4 b = mix(texture_texel(tex, p.x, p.y + 1), texture_texel(tex, p.x + 1, p.y + 1), f.x);
    return mix(a, b, f.y);
}

#endif
