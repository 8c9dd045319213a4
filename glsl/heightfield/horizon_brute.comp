#version 460
// The height-field thesis lighting kernel variant: see heightfield/shade.glsl.
#define HF_BRUTE
#define HF_HORIZON_ONLY
#include "heightfield/shade.glsl"
