#version 460
// Environment light in SH for a constant sky (the height-field thesis section 1.7, "computed once each frame"):
// c_00 = 2 sqrt(pi) L, the rest 0, exactly. An image environment is projected by the SH core's
// pass instead (glsl/sh/project_*.comp, src/sh/gpu.rs). Output: rgb per coefficient, bands^2
// entries.
#include "common/sh.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) writeonly buffer EnvSh { vec4 c[]; } env_sh;

layout(push_constant) uniform EnvPush {
    vec4 constant;  // rgb: constant radiance
    int bands;
} pc;

void main() {
    int t = int(gl_LocalInvocationIndex);
    int nb = clamp(pc.bands, 1, SH_MAX_BANDS);
    if (t < nb * nb) env_sh.c[t] = vec4(t == 0 ? 2.0 * sqrt(SH_PI) * pc.constant.rgb : vec3(0.0), 0.0);
}
