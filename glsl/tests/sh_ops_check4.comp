// Check kernel for common/sh.glsl with SH_ROTATE_MAX_BANDS 4 (bands 4..7 of an 8-band rotation
// come out 0); see sh_ops_check.glsl.
#version 460
#define SH_ROTATE_MAX_BANDS 4
#include "tests/sh_ops_check.glsl"
