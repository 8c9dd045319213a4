#version 460
// SH projection, second dispatch: thread k adds coefficient k's partial sums of every group of
// project_equirect.comp / project_cube.comp, in group order (deterministic), and writes
// sh_out.c[k] = (r, g, b, 0) for k < bands^2.
#include "common/sh.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) readonly buffer Partials { vec4 v[]; } partials;
layout(set = 0, binding = 1, std430) writeonly buffer ShOut { vec4 c[]; } sh_out;

layout(push_constant) uniform ReducePush {
    ivec4 dims;  // x: groups, y: bands
} pc;

void main() {
    int k = int(gl_LocalInvocationIndex);
    int nb = clamp(pc.dims.y, 1, SH_MAX_BANDS);
    if (k >= nb * nb) return;
    vec3 sum = vec3(0.0);
    for (int g = 0; g < pc.dims.x; ++g) sum += partials.v[g * 64 + k].rgb;
    sh_out.c[k] = vec4(sum, 0.0);
}
