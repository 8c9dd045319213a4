#version 460
// SH projection of a cube-map environment: see sh/project.glsl.
#define SH_PROJECT_CUBE 1
#include "sh/project.glsl"
