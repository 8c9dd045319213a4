// Deterministic random numbers for the reference path tracer: every (pixel, sample index, seed)
// starts its own PCG stream, so a sample's value does not depend on how samples are batched.
#ifndef PENUMBRA_REFERENCE_RNG_GLSL
#define PENUMBRA_REFERENCE_RNG_GLSL

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

#endif
