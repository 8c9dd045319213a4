#version 460
// The height-field thesis lighting kernel variant: see heightfield/shade.glsl.
#define HF_PYRAMID
#define HF_LIGHT
#include "heightfield/shade.glsl"
