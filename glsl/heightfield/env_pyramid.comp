#version 460
// Seed 001 lighting kernel variant: see heightfield/shade.glsl.
#define HF_PYRAMID
#include "heightfield/shade.glsl"
