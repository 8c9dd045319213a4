#version 460
// SH projection of an equirectangular environment map: see sh/project.glsl.
#include "sh/project.glsl"
