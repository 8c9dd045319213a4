// What the scene holds, as specialization constants set by src/reference/features.rs. llvmpipe
// runs both sides of every branch, lanes masked off, even where every lane goes the same way or
// the condition is uniform: code for a kind of light or material the scene does not have costs
// as much as code it runs. With a constant false the compiler drops that code. Each is true by
// default, which traces every scene correctly; the host sets it false only where the scene has
// none of the thing, so the image is the same bit for bit.
#ifndef PENUMBRA_REFERENCE_FEATURES_GLSL
#define PENUMBRA_REFERENCE_FEATURES_GLSL

// Some material has a texture map (albedo, normal or specular).
layout(constant_id = 0) const bool SCENE_HAS_MAPS = true;
// Some material has an opacity below 1 (stochastic transparency).
layout(constant_id = 1) const bool SCENE_HAS_TRANSLUCENCY = true;
// Some material has a non-zero Blinn-Phong colour.
layout(constant_id = 2) const bool SCENE_HAS_SPECULAR = true;
// Some material has a non-zero diffuse transmittance.
layout(constant_id = 3) const bool SCENE_HAS_TRANSMISSION = true;
// Punctual (point, spot, directional), sphere and quad lights.
layout(constant_id = 4) const bool SCENE_HAS_PUNCTUAL_LIGHTS = true;
layout(constant_id = 5) const bool SCENE_HAS_SPHERE_LIGHTS = true;
layout(constant_id = 6) const bool SCENE_HAS_QUAD_LIGHTS = true;
// The environment is a map (equirect or cube) rather than a constant colour, and is sampled.
layout(constant_id = 7) const bool SCENE_HAS_ENVIRONMENT_MAP = true;
layout(constant_id = 8) const bool SCENE_SAMPLES_ENVIRONMENT = true;
// Next-event estimation: 0 visits every light, 1 draws one (FLAG_ONE_LIGHT), 2 reads the flag.
layout(constant_id = 9) const uint NEE_MODE = 2u;
// How rays walk the BVH (src/reference/features.rs, BvhWalk): false, the stack walk
// (trace_triangles); true, the stackless walk ordered per ray octant (trace_triangles_ordered).
// The same closest hits either way; the host picks the faster on the device.
layout(constant_id = 10) const bool BVH_WALK_ORDERED = false;
// Where the main draws come from (reference/rng.glsl, `sample1` and `sample2`): false, the PCG
// stream (independent samples); true, scrambled Sobol points, stratified over a pixel's samples.
layout(constant_id = 11) const bool SAMPLER_SOBOL = false;
// How many independently scrambled replicates the Sobol sampler splits a pixel's samples into
// (reference/rng.glsl): always set by the host from src/reference/mod.rs SOBOL_REPLICATES, which
// also reads the replicates back; the 8 here is only a default.
layout(constant_id = 12) const uint SOBOL_REPLICATES = 8u;

#endif
