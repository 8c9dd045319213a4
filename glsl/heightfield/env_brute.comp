#version 460
// The height-field thesis lighting kernel variant: see heightfield/shade.glsl.
#define HF_BRUTE
#include "heightfield/shade.glsl"
