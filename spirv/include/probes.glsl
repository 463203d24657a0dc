// The irradiance probe volume (after DDGI: Majercik et al. 2019, "Dynamic Diffuse Global
// Illumination with Ray-Traced Irradiance Fields"): a grid of probes, each with an octahedral
// map of irradiance and one of the mean and mean squared distance to the nearest surface, both
// with a one-texel border that makes bilinear filtering wrap across the octahedron's edges.
// src/passes/probes.rs builds and updates the volume; this file holds what both the update
// (probe_trace.comp, probe_blend.comp) and the lighting pass (deferred.comp) agree on.
//
// The including kernel declares `probe_texels` (the GpuProbeGrid header, then one state texel
// per probe), `probe_irradiance` and `probe_distance` (rgba32f texels), and includes
// gbuffer.glsl (oct_encode, oct_decode) before this file.
#ifndef UMBRA_PROBES_GLSL
#define UMBRA_PROBES_GLSL

const uint PROBE_IRRADIANCE_SIDE = PROBE_IRRADIANCE_TEXELS + 2u;
const uint PROBE_DISTANCE_SIDE = PROBE_DISTANCE_TEXELS + 2u;

vec4 probe_header(uint k) { return uintBitsToFloat(imageLoad(probe_texels, int(k))); }
uvec3 probe_counts() { return imageLoad(probe_texels, 2).xyz; }
uvec4 probe_state(uint i) { return imageLoad(probe_texels, int(PROBE_HEADER_TEXELS + i)); }

uint probe_index(uvec3 c, uvec3 counts) { return c.x + counts.x * (c.y + counts.y * c.z); }

uvec3 probe_coords(uint i, uvec3 counts) {
    return uvec3(i % counts.x, (i / counts.x) % counts.y, i / (counts.x * counts.y));
}

vec3 probe_position(uint i) {
    return probe_header(0u).xyz + probe_header(1u).xyz * vec3(probe_coords(i, probe_counts()));
}

// Ray k of n from a probe: a spherical Fibonacci point set (uniform over the sphere), turned by
// the update's random rotation (rows r0, r1, r2) so successive updates see other directions.
vec3 probe_ray_direction(uint k, uint n, vec3 r0, vec3 r1, vec3 r2) {
    const float GOLDEN = 1.6180339887498949;
    float z = 1.0 - (2.0 * float(k) + 1.0) / float(n);
    float r = sqrt(max(1.0 - z * z, 0.0));
    float phi = 2.0 * PI * fract(float(k) / GOLDEN);
    vec3 d = vec3(r * cos(phi), r * sin(phi), z);
    return vec3(dot(r0, d), dot(r1, d), dot(r2, d));
}

// The direction a texel of a bordered octahedral map of `side` = interior + 2 texels stands for:
// a border texel repeats the interior texel across the octahedron's edge (the edge's mirror
// image along it; corners take the opposite corner), so it stands for that texel's direction.
vec3 probe_texel_direction(uvec2 texel, uint side) {
    uint n = side - 2u;
    ivec2 t = ivec2(texel);
    int last = int(side) - 1;
    bool border_x = t.x == 0 || t.x == last;
    bool border_y = t.y == 0 || t.y == last;
    if (border_x && border_y) {
        t = ivec2(t.x == 0 ? int(n) : 1, t.y == 0 ? int(n) : 1);
    } else if (border_x) {
        t = ivec2(t.x == 0 ? 1 : int(n), last - t.y);
    } else if (border_y) {
        t = ivec2(last - t.x, t.y == 0 ? 1 : int(n));
    }
    vec2 uv = (vec2(t - 1) + 0.5) / float(n);
    return oct_decode(uv * 2.0 - 1.0);
}

// Bilinear lookup of probe i's bordered octahedral map (`side` texels a side, `side`² per probe)
// along unit direction d: the four texel indices and their weights.
void probe_map_taps(uint i, uint side, vec3 d, out uvec4 idx, out vec4 w) {
    float n = float(side - 2u);
    vec2 p = (oct_encode(d) * 0.5 + 0.5) * n + 0.5;  // from the first interior texel's centre
    vec2 base = clamp(floor(p), vec2(0.0), vec2(n));
    vec2 f = clamp(p - base, vec2(0.0), vec2(1.0));
    uint o = i * side * side + uint(base.y) * side + uint(base.x);
    idx = uvec4(o, o + 1u, o + side, o + side + 1u);
    w = vec4((1.0 - f.x) * (1.0 - f.y), f.x * (1.0 - f.y), (1.0 - f.x) * f.y, f.x * f.y);
}

vec3 probe_irradiance_at(uint i, vec3 d) {
    uvec4 idx;
    vec4 w;
    probe_map_taps(i, PROBE_IRRADIANCE_SIDE, d, idx, w);
    return w.x * imageLoad(probe_irradiance, int(idx.x)).rgb + w.y * imageLoad(probe_irradiance, int(idx.y)).rgb
        + w.z * imageLoad(probe_irradiance, int(idx.z)).rgb + w.w * imageLoad(probe_irradiance, int(idx.w)).rgb;
}

vec2 probe_distance_at(uint i, vec3 d) {
    uvec4 idx;
    vec4 w;
    probe_map_taps(i, PROBE_DISTANCE_SIDE, d, idx, w);
    return w.x * imageLoad(probe_distance, int(idx.x)).rg + w.y * imageLoad(probe_distance, int(idx.y)).rg
        + w.z * imageLoad(probe_distance, int(idx.z)).rg + w.w * imageLoad(probe_distance, int(idx.w)).rg;
}

// Irradiance at p (shading normal n, unit wo towards the viewer) from the eight probes of the
// cell around p moved by the normal and view biases: trilinear weights, times a smooth
// back-face term (probes behind the surface count less), times Chebyshev's bound on the
// probability that the probe sees the moved point (when the grid's PROBE_VISIBILITY is set),
// with weights under 0.2 crushed towards 0 (DDGI's choices). Inactive probes (inside geometry)
// and probes never updated are left out; 0 when no probe counts.
vec3 probe_volume_irradiance(vec3 p, vec3 n, vec3 wo) {
    vec4 h0 = probe_header(0u);
    vec4 h1 = probe_header(1u);
    uvec4 h2 = imageLoad(probe_texels, 2);
    vec3 origin = h0.xyz;
    vec3 spacing = h1.xyz;
    uvec3 counts = h2.xyz;
    bool visibility = (h2.w & PROBE_VISIBILITY) != 0u;
    vec3 pb = p + n * h0.w + wo * h1.w;
    vec3 g = (pb - origin) / spacing;
    ivec3 last = ivec3(counts) - 1;
    ivec3 base = clamp(ivec3(floor(g)), ivec3(0), max(last - 1, ivec3(0)));
    vec3 a = clamp(g - vec3(base), vec3(0.0), vec3(1.0));
    vec3 sum = vec3(0.0);
    float weights = 0.0;
    for (uint c = 0u; c < 8u; ++c) {
        uvec3 off = uvec3(c & 1u, (c >> 1u) & 1u, (c >> 2u) & 1u);
        uvec3 cell = uvec3(min(base + ivec3(off), last));
        uint i = probe_index(cell, counts);
        uvec4 state = probe_state(i);
        if ((state.x & PROBE_ACTIVE) == 0u || state.y == 0u) {
            continue;
        }
        vec3 pp = origin + spacing * vec3(cell);
        vec3 to_probe = pp - p;
        float len = length(to_probe);
        float facing = len > 0.0 ? (dot(to_probe / len, n) + 1.0) * 0.5 : 1.0;
        float w = facing * facing + 0.2;
        if (visibility) {
            vec3 from_probe = pb - pp;
            float d = length(from_probe);
            if (d > 0.0) {
                vec2 m = probe_distance_at(i, from_probe / d);
                if (d > m.x) {
                    float variance = abs(m.y - m.x * m.x);
                    float excess = d - m.x;
                    float chebyshev = variance / (variance + excess * excess);
                    w *= chebyshev * chebyshev * chebyshev;
                }
            }
        }
        w = max(w, 1e-6);
        const float CRUSH = 0.2;
        if (w < CRUSH) {
            w *= w * w / (CRUSH * CRUSH);
        }
        vec3 tri = mix(vec3(1.0) - a, a, vec3(off));
        w *= tri.x * tri.y * tri.z;
        sum += w * probe_irradiance_at(i, n);
        weights += w;
    }
    return weights > 0.0 ? sum / weights : vec3(0.0);
}

#endif
