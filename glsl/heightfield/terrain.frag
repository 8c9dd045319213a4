#version 460
// Exit radiance of the height field: albedo times the accumulated shading (L . (V * C), which
// already holds the Lambert 1/pi), plus the material's emission.
layout(set = 0, binding = 2) uniform sampler2D shading;

layout(push_constant) uniform Terrain {
    vec4 origin;
    vec4 albedo;
    vec4 emission;
} terrain;

layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;

void main() {
    out_radiance = vec4(terrain.albedo.rgb * texture(shading, in_uv).rgb + terrain.emission.rgb, 1.0);
}
