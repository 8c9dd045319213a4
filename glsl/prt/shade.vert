#version 460
// Run-time PRT shading (src/lighting/prt/mod.rs, Listing 2.8 per vertex): the vertex's transfer
// (two SH keys blended, Listing 3.1; one key for a static scene) dotted with the light's 16 RGB
// coefficients. Exit radiance is albedo / pi times this (shade.frag).
#include "common/frame.glsl"
#define PENUMBRA_SCENE_VERTEX
#include "common/scene.glsl"

layout(set = 0, binding = 1) readonly buffer Transfer { vec4 items[]; } transfer;  // 4 vec4 per vertex per key
layout(set = 0, binding = 2) readonly buffer Light {
    vec4 coeffs[16];  // rgb, zero past the coefficients in use
    uvec4 keys;       // x: first key, y: second key, z: vertices per key, w: coefficients in use
    vec4 blend;       // x: weight of the second key
} light;

layout(location = 0) out vec3 out_irradiance;
layout(location = 1) out vec2 out_uv;
layout(location = 2) out vec3 out_normal;
layout(location = 3) out vec3 out_world;

void main() {
    vec4 world = draw.model * vec4(in_position, 1.0);
    uint v = uint(gl_VertexIndex);
    vec3 e = vec3(0.0);
    for (int g = 0; g < 4; ++g) {
        vec4 a = transfer.items[(light.keys.x * light.keys.z + v) * 4u + uint(g)];
        vec4 b = transfer.items[(light.keys.y * light.keys.z + v) * 4u + uint(g)];
        vec4 t = mix(a, b, light.blend.x);
        for (int c = 0; c < 4; ++c) {
            e += t[c] * light.coeffs[4 * g + c].rgb;
        }
    }
    out_irradiance = e;
    out_uv = in_uv;
    out_normal = transpose(inverse(mat3(draw.model))) * in_normal;
    out_world = world.xyz;
    gl_Position = frame.view_proj * world;
}
