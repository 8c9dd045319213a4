#version 460
// Segments for the base term alone: no vertex colours bound, so no relighting pass is needed.
#include "bsp_lights/segments_body.glsl"
