// Counter-based random numbers: a pure function of (pixel, sample, bounce, dimension, seed), so
// any sample of any pixel is reproducible and accumulation is bit-identical for the same seed.
// rand4 hashes all of them (independent numbers); the path tracer draws qmc4's (below), which
// hashes all but the sample and stratifies a pixel's samples.
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
// With sample reuse (bsdf.glsl's SAMPLE_REUSE) a choice takes the number its option's sample
// starts from: the light (map or emitters), the emissive triangle and the BSDF's lobe by y.
const uint RNG_EMISSIVE_NEE = 1u;  // emissive triangle by power (x), point on it (yz), map or triangles (w)
const uint RNG_BSDF = 2u;          // BSDF lobe (x), direction (yz), Russian roulette (w)
const uint RNG_ENV_NEE = 3u;       // environment map sample (without sample reuse)
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

// Low-discrepancy numbers for the path tracer: per (pixel, stream), two 2D Sobol sequences
// (dimensions 0 and 1, a (0,2)-sequence), each shuffled and Owen-scrambled by hashing (Burley
// 2020, "Practical Hash-based Owen Scrambling"). The first 2^m samples of a pixel's stream put
// exactly one point of each pair into every 2^-m-area elementary interval (a (0,m,2)-net, for
// any m), so a 2D integrand (a pixel's footprint, a BSDF lobe, a point on a light) is stratified
// at every sample count, while every single number stays uniform on [0, 1) and independent of the
// other streams' and pixels' (their own scrambles: a pixel's error stays white noise). The two
// pairs of a stream are shuffled apart (padding), so they stratify each on its own. Component
// layout: (y, z) is one pair (the 2D sample: a BSDF direction, a point on a triangle), (x, w) the
// other (the BSDF's lobe choice and Russian roulette; the triangle's pick and the choice between
// the environment and the emitters).

// Base-2 Owen scrambling of a bit-reversed integer (its lowest bit the first binary digit): each
// bit flipped by a hash of the bits below it, the Laine-Karras permutation with Vegdahl's
// constants (2021, "Building a better LK hash").
uint owen_reversed(uint x, uint seed) {
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16u) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

// The digits of Sobol dimension 1 (bit r of the result is the point's binary digit r + 1 after
// the point) for index bits `a`: digit r is the XOR of the index bits k whose binomial
// coefficient C(k, r) is odd, which by Lucas's theorem are those whose bits contain r's. That
// sum over supersets takes five shifts (one per bit of r).
uint sobol1_digits(uint a) {
    a ^= (a >> 1u) & 0x55555555u;
    a ^= (a >> 2u) & 0x33333333u;
    a ^= (a >> 4u) & 0x0f0f0f0fu;
    a ^= (a >> 8u) & 0x00ff00ffu;
    a ^= (a >> 16u) & 0x0000ffffu;
    return a;
}

// Point `index` of a 2D Sobol sequence (`reversed` = bitfieldReverse(index)) shuffled by
// seeds.x and its two dimensions Owen-scrambled by seeds.y and seeds.z. Dimension 0's digits are
// the index's bits (van der Corput), so both dimensions are scrambled in reversed form and
// reversed once.
vec2 sobol2(uint reversed, uvec3 seeds) {
    // The index Owen-scrambled from its highest bit: the first 2^m indices become one aligned
    // block of 2^m, whose points are a (0,m,2)-net too.
    uint i = bitfieldReverse(owen_reversed(reversed, seeds.x));
    uint x = bitfieldReverse(owen_reversed(i, seeds.y));
    uint y = bitfieldReverse(owen_reversed(sobol1_digits(i), seeds.z));
    return vec2(uvec2(x, y) >> 8u) * (1.0 / 16777216.0);
}

// The part of u in [lo, lo + share), stretched back over [0, 1): after a choice by u, a number
// for the chosen option's own sample (sample reuse). A low-discrepancy number keeps its
// stratification so (an elementary interval of a net, stretched, is a net's again); it spends
// log2(1 / share) of its 24 bits, and on independent numbers it would multiply pcg4d's weakest
// bits by 1 / share (SAMPLE_REUSE: only the path tracer's low-discrepancy numbers take it).
float stretch(float u, float lo, float share) {
    return clamp((u - lo) / share, 0.0, 0.99999994);
}

// An integer hash (Wellons' lowbias32): a second seed from one of pcg4d's.
uint hash_u32(uint x) {
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return x;
}

// Four numbers in [0, 1) for (pixel, sample, stream), low-discrepancy over a pixel's samples:
// (y, z) and (x, w) are each a point of a scrambled 2D Sobol sequence (above).
vec4 qmc4(uvec2 pixel, uint sample_index, uint stream, uint seed) {
    uvec4 h = pcg4d(uvec4(pixel, stream, seed * 0x9E3779B9u + 0x51ed27u));
    uint reversed = bitfieldReverse(sample_index);
    vec2 a = sobol2(reversed, uvec3(h.x, h.y, hash_u32(h.y)));
    vec2 b = sobol2(reversed, uvec3(h.z, h.w, hash_u32(h.w)));
    return vec4(b.x, a.x, a.y, b.y);
}

#endif
