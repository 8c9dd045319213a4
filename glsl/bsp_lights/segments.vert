#version 460
// Segments with the direct term: reads the GEMV's vertex colours.
#define BSP_DIRECT 1
#include "bsp_lights/segments_body.glsl"
