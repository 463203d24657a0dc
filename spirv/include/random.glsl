// Counter-based random numbers: a pure hash of (pixel, sample, bounce, dimension, seed), so any
// sample of any pixel is reproducible and accumulation is bit-identical for the same seed.
#ifndef UMBRA_RANDOM_GLSL
#define UMBRA_RANDOM_GLSL

// PCG4D (Jarzynski and Olano 2020, "Hash Functions for GPU Rendering").
uvec4 pcg4d(uvec4 v) {
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    v ^= v >> 16u;
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    return v;
}

// Random-number streams: a path's bounce `depth` draws from streams rng_stream(depth, use), four
// numbers each, one stream per use, so changing how one use consumes numbers leaves the others'
// numbers unchanged.
const uint RNG_STREAMS_PER_BOUNCE = 8u;
const uint RNG_CAMERA = 0u;        // pixel jitter (xy), at depth 0
const uint RNG_EMISSIVE_NEE = 1u;  // emissive triangle by power (x), point on it (yz)
const uint RNG_BSDF = 2u;          // BSDF sample (xyz), Russian roulette (w)
const uint RNG_ENV_NEE = 3u;       // environment map sample
const uint RNG_PUNCTUAL = 4u;      // punctual light pick (x)
const uint RNG_DISPERSION = 5u;    // colour channel through a dispersive volume (x)
// RIS (path.glsl's path_ris) at bounce `depth`: candidate k draws its light sample from stream
// rng_stream(ris_depth(depth) + k, RNG_RIS_CANDIDATE) and whether the reservoir keeps it from
// rng_stream(ris_depth(depth) + k, RNG_RIS_PICK) (x): these two uses are RIS's at every "depth".
// Each bounce has RIS_DEPTHS of those "depths": 256 for the candidates (DirectSampling's most),
// then, at the first hit, the reuse's (ris_reuse.glsl's RIS_REUSE_DEPTH).
const uint RNG_RIS_CANDIDATE = 6u;
const uint RNG_RIS_PICK = 7u;
const uint RIS_DEPTHS = 512u;

uint ris_depth(uint depth) {
    return depth * RIS_DEPTHS;
}

uint rng_stream(uint depth, uint use) {
    return depth * RNG_STREAMS_PER_BOUNCE + use;
}

// Four uniform numbers in [0, 1) for (pixel, sample, stream).
vec4 rand4(uvec2 pixel, uint sample_index, uint stream, uint seed) {
    uvec4 h = pcg4d(uvec4(pixel, sample_index, stream ^ (seed * 0x9E3779B9u)));
    return vec4(h >> 8u) * (1.0 / 16777216.0);
}

#endif
