// Deterministic random numbers for the reference path tracer: every (pixel, sample index, seed)
// starts its own PCG stream, so a sample's value does not depend on how samples are batched.
// The draws that matter most (in 2D the point in the pixel, the point on an area light, the
// environment direction and the BSDF direction; in 1D the BSDF's lobe and Russian roulette) go
// through `sample2` and `sample1`, which with the Sobol sampler (spec constant SAMPLER_SOBOL,
// src/reference/features.rs) take them from a scrambled low-discrepancy sequence instead.
#ifndef PENUMBRA_REFERENCE_RNG_GLSL
#define PENUMBRA_REFERENCE_RNG_GLSL

#include "reference/features.glsl"

// PCG-RXS-M-XS 32 as a hash (Jarzynski and Olano, "Hash Functions for GPU Rendering", 2020).
uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

uint rng_start(uint pixel, uint sample_index, uint seed) {
    return pcg_hash(pixel ^ pcg_hash(sample_index ^ pcg_hash(seed)));
}

// Uniform in [0, 1): the top 24 bits of the next PCG output.
float rand(inout uint state) {
    state = state * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    word = (word >> 22u) ^ word;
    return float(word >> 8u) * (1.0 / 16777216.0);
}

// The Sobol sampler: per pixel and per 2D draw (a key: what is drawn, at which depth, for which
// light) the first two dimensions of Sobol's sequence, shuffled and Owen-scrambled with hashes
// (Burley, "Practical Hash-based Owen Scrambling", JCGT 2020). A pixel's samples form
// SOBOL_REPLICATES independent replicates (sample index modulo the count), each with scrambles of
// its own, and a replicate's k-th sample takes its sequence's k-th point (after the shuffle), so
// any prefix of a replicate's samples - whatever the batching - is a stratified set in every 2D
// draw, and each draw is uniform on its own: the estimate is unbiased, and its error falls faster
// than independent sampling's wherever the integrand is smooth enough in those two dimensions.
// The replicates being independent, the scatter of their means measures that error (a single
// scramble's samples are not independent, so their scatter would overstate it). Draws with
// different keys use independent scrambles (padding), so they are independent of each other
// within a sample. The sample index and the scramble seed are set once per sample by
// `sampler_start`; they are per-invocation state like the PCG streams.
uint sampler_index = 0u;
uint sampler_pixel_seed = 0u;

void sampler_start(uint pixel, uint sample_index, uint seed) {
    sampler_index = sample_index / SOBOL_REPLICATES;
    // Independent of the sample's place in its replicate: the replicate's samples share the scramble.
    uint replicate = sample_index % SOBOL_REPLICATES;
    sampler_pixel_seed = pcg_hash(pcg_hash(pixel ^ pcg_hash(seed ^ 0x51ed270bu)) ^ pcg_hash(replicate + 0x2545f491u));
}

// Laine and Karras's permutation as improved by Burley: each output bit depends only on the
// input bits below it, so after a bit reversal it is a nested uniform (Owen) scramble.
uint owen_permutation(uint x, uint seed) {
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16u) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

uint nested_uniform_scramble(uint x, uint seed) {
    return bitfieldReverse(owen_permutation(bitfieldReverse(x), seed));
}

// Sobol's second dimension as a 32-bit fraction: the index's bits times the upper Pascal
// matrix mod 2 (direction numbers v1 = 2^31, v(k+1) = vk ^ (vk >> 1)); the first dimension is
// the bit reversal. Written out: llvmpipe counts every loop iteration against its 65,535 limit.
uint sobol_second(uint i) {
    uint r = 0u;
    r ^= 0x80000000u & (0u - ((i >> 0u) & 1u));
    r ^= 0xc0000000u & (0u - ((i >> 1u) & 1u));
    r ^= 0xa0000000u & (0u - ((i >> 2u) & 1u));
    r ^= 0xf0000000u & (0u - ((i >> 3u) & 1u));
    r ^= 0x88000000u & (0u - ((i >> 4u) & 1u));
    r ^= 0xcc000000u & (0u - ((i >> 5u) & 1u));
    r ^= 0xaa000000u & (0u - ((i >> 6u) & 1u));
    r ^= 0xff000000u & (0u - ((i >> 7u) & 1u));
    r ^= 0x80800000u & (0u - ((i >> 8u) & 1u));
    r ^= 0xc0c00000u & (0u - ((i >> 9u) & 1u));
    r ^= 0xa0a00000u & (0u - ((i >> 10u) & 1u));
    r ^= 0xf0f00000u & (0u - ((i >> 11u) & 1u));
    r ^= 0x88880000u & (0u - ((i >> 12u) & 1u));
    r ^= 0xcccc0000u & (0u - ((i >> 13u) & 1u));
    r ^= 0xaaaa0000u & (0u - ((i >> 14u) & 1u));
    r ^= 0xffff0000u & (0u - ((i >> 15u) & 1u));
    r ^= 0x80008000u & (0u - ((i >> 16u) & 1u));
    r ^= 0xc000c000u & (0u - ((i >> 17u) & 1u));
    r ^= 0xa000a000u & (0u - ((i >> 18u) & 1u));
    r ^= 0xf000f000u & (0u - ((i >> 19u) & 1u));
    r ^= 0x88008800u & (0u - ((i >> 20u) & 1u));
    r ^= 0xcc00cc00u & (0u - ((i >> 21u) & 1u));
    r ^= 0xaa00aa00u & (0u - ((i >> 22u) & 1u));
    r ^= 0xff00ff00u & (0u - ((i >> 23u) & 1u));
    r ^= 0x80808080u & (0u - ((i >> 24u) & 1u));
    r ^= 0xc0c0c0c0u & (0u - ((i >> 25u) & 1u));
    r ^= 0xa0a0a0a0u & (0u - ((i >> 26u) & 1u));
    r ^= 0xf0f0f0f0u & (0u - ((i >> 27u) & 1u));
    r ^= 0x88888888u & (0u - ((i >> 28u) & 1u));
    r ^= 0xccccccccu & (0u - ((i >> 29u) & 1u));
    r ^= 0xaaaaaaaau & (0u - ((i >> 30u) & 1u));
    r ^= 0xffffffffu & (0u - ((i >> 31u) & 1u));
    return r;
}

// What identifies a draw within a sample: where it is used, the path depth and the light.
// 2D draws:
const uint DRAW_PIXEL = 0u;
const uint DRAW_BSDF = 1u;
const uint DRAW_LIGHT = 2u;
const uint DRAW_ENVIRONMENT = 3u;
// 1D draws (`sample1`): which lobe the BSDF samples, and Russian roulette.
const uint DRAW_LOBE = 4u;
const uint DRAW_ROULETTE = 5u;
// Keys are distinct below these bounds; draws past them come from the PCG stream.
const uint SOBOL_DEPTHS = 1024u;
const uint SOBOL_LIGHTS = 1u << 19u;

uint draw_key(uint use, uint depth, uint light) {
    return use + 8u * (depth + SOBOL_DEPTHS * light);
}

// The scramble seed of a draw: pcg_hash is a bijection, so distinct keys give distinct seeds.
uint draw_seed(uint use, uint depth, uint light) {
    return pcg_hash(sampler_pixel_seed ^ pcg_hash(draw_key(use, depth, light)));
}

// The sample's index in the draw's shuffled sequence, and that point's first coordinate (van der
// Corput) Owen-scrambled, both from the draw's seed; a 32-bit fraction's top 24 bits in [0, 1).
uint shuffled_index(uint seed) {
    return nested_uniform_scramble(sampler_index, seed);
}

uint sobol_first_scrambled(uint i, uint seed) {
    return nested_uniform_scramble(bitfieldReverse(i), pcg_hash(seed ^ 0x68bc21ebu));
}

float unit_fraction(uint x) {
    return float(x >> 8u) * (1.0 / 16777216.0);
}

// A 1D draw: Sobol's first dimension, shuffled and scrambled per key as the 2D draws are;
// stratified over a replicate's samples like them.
float sample1(uint use, uint depth, inout uint rng) {
    if (!SAMPLER_SOBOL || depth >= SOBOL_DEPTHS) {
        return rand(rng);
    }
    uint seed = draw_seed(use, depth, 0u);
    return unit_fraction(sobol_first_scrambled(shuffled_index(seed), seed));
}

vec2 sample2(uint use, uint depth, uint light, inout uint rng) {
    if (!SAMPLER_SOBOL || depth >= SOBOL_DEPTHS || light >= SOBOL_LIGHTS) {
        return vec2(rand(rng), rand(rng));
    }
    uint seed = draw_seed(use, depth, light);
    uint i = shuffled_index(seed);
    uint y = nested_uniform_scramble(sobol_second(i), pcg_hash(seed ^ 0x02e5be93u));
    return vec2(unit_fraction(sobol_first_scrambled(i, seed)), unit_fraction(y));
}

#endif
