#version 460
// The environment seen where nothing was drawn: the radiance of the equirect or cube texel the
// view ray falls in (nearest, like the reference's lookup).
#include "common/lights.glsl"
#include "common/cube.glsl"

layout(set = 0, binding = 0) uniform sampler2D environment_map;

layout(push_constant) uniform Sky {
    mat4 inverse_view_proj;
    uint cube;  // 1: the map is six square faces stacked (common/cube.glsl)
} sky;

layout(location = 0) in vec2 in_ndc;
layout(location = 0) out vec4 out_radiance;

// Matches Environment::equirect_uv in src/scene/types.rs.
vec2 equirect_uv(vec3 d) {
    return vec2(0.5 + atan(d.x, -d.z) / (2.0 * PI), acos(clamp(d.y, -1.0, 1.0)) / PI);
}

void main() {
    // Two points on the view ray: the near plane (depth 0) and the point at depth 0.5.
    vec4 a = sky.inverse_view_proj * vec4(in_ndc, 0.0, 1.0);
    vec4 b = sky.inverse_view_proj * vec4(in_ndc, 0.5, 1.0);
    vec3 dir = normalize(b.xyz / b.w - a.xyz / a.w);
    if (sky.cube != 0u) {
        vec2 st;
        uint face = cube_face(dir, st);
        uvec2 t = cube_texel(face, st, uint(textureSize(environment_map, 0).x));
        out_radiance = vec4(texelFetch(environment_map, ivec2(t), 0).rgb, 1.0);
    } else {
        out_radiance = vec4(texture(environment_map, equirect_uv(dir)).rgb, 1.0);
    }
}
