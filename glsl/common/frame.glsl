// Per-frame camera data (set 0). Matches `FrameUniforms` in src/lighting/mod.rs.
#ifndef PENUMBRA_FRAME_GLSL
#define PENUMBRA_FRAME_GLSL

layout(set = 0, binding = 0) uniform FrameUniforms {
    mat4 view_proj;
    vec4 camera_pos;   // xyz: eye position (world)
    vec4 ambient;      // rgb: constant ambient radiance reflected as rho * ambient
    uvec4 counts;      // x: number of lights
    // Irradiance of the environment as 3-band SH in the SH frame (sh_world_to_sh), rgb:
    // E(n) = sum_i env_irradiance[i] * Y_i(n). Exact for a constant sky; no visibility.
    vec4 env_irradiance[9];
} frame;

#endif
