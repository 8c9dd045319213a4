#version 460
// Accumulation (the height-field thesis section 5.3): environment plus every light, clamped at zero (the SH
// product can go negative; the thesis's 8-bit targets clamped implicitly).
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D env_radiance;
layout(set = 0, binding = 1) uniform sampler2DArray light_radiance;
layout(set = 0, binding = 2, rgba32f) uniform writeonly image2D shading;

layout(push_constant) uniform Accumulate { int res; int has_env; int lights; } pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= pc.res || p.y >= pc.res) return;
    vec3 sum = pc.has_env != 0 ? texelFetch(env_radiance, p, 0).rgb : vec3(0.0);
    for (int k = 0; k < pc.lights; ++k) sum += texelFetch(light_radiance, ivec3(p, k), 0).rgb;
    imageStore(shading, p, vec4(max(sum, vec3(0.0)), 1.0));
}
