// Check kernel for common/sh.glsl with the default SH_ROTATE_MAX_BANDS (8); see sh_ops_check.glsl.
#version 460
#include "tests/sh_ops_check.glsl"
