#version 460
// Scatter injection of the camera's G-buffer's surfels (lpv/inject.glsl): blocking only (they
// carry no flux), and none for a surface the RSM already holds.
#define SKIP_HELD_BY_RSM
#include "lpv/inject.glsl"
