#version 460
// The height-field thesis lighting kernel variant: see heightfield/shade.glsl.
#define HF_PYRAMID
#include "heightfield/shade.glsl"
