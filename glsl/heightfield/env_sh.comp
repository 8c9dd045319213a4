#version 460
// Environment light in SH (seed 001 section 1.7, "computed once each frame"): mode 0, a constant
// radiance (c_00 = 2 sqrt(pi) L, the rest 0, exactly); mode 1, the equirectangular map projected
// with exact texel solid angles. Output: rgb per coefficient, bands^2 entries.
#include "common/sh.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 0) uniform sampler2D env_map;
layout(set = 0, binding = 1, std430) writeonly buffer EnvSh { vec4 c[]; } env_sh;

layout(push_constant) uniform EnvPush {
    vec4 constant;  // rgb: constant radiance (mode 0)
    int mode;
    int bands;
} pc;

shared vec3 partial[64];

void main() {
    int t = int(gl_LocalInvocationIndex);
    int nc = pc.bands * pc.bands;
    if (pc.mode == 0) {
        if (t < nc) env_sh.c[t] = vec4(t == 0 ? 2.0 * sqrt(SH_PI) * pc.constant.rgb : vec3(0.0), 0.0);
        return;
    }
    ivec2 size = textureSize(env_map, 0);
    vec3 acc[SH_MAX_COEFFS];
    for (int k = 0; k < SH_MAX_COEFFS; ++k) acc[k] = vec3(0.0);
    for (int i = t; i < size.x * size.y; i += 64) {
        ivec2 texel = ivec2(i % size.x, i / size.x);
        vec3 dir = sh_world_to_sh(sh_equirect_texel_dir_world(texel, size));
        float y[SH_MAX_COEFFS];
        sh_eval_bands(dir, pc.bands, y);
        vec3 l = texelFetch(env_map, texel, 0).rgb * sh_equirect_texel_solid_angle(texel.y, size.x, size.y);
        for (int k = 0; k < nc; ++k) acc[k] += l * y[k];
    }
    for (int k = 0; k < nc; ++k) {
        partial[t] = acc[k];
        barrier();
        for (int s = 32; s > 0; s >>= 1) {
            if (t < s) partial[t] += partial[t + s];
            barrier();
        }
        if (t == 0) env_sh.c[k] = vec4(partial[0], 0.0);
        barrier();
    }
}
