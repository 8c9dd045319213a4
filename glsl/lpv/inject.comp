#version 460
// Scatter injection of the RSM's surfels (lpv/inject.glsl).
#include "lpv/inject.glsl"
