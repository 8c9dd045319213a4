#version 460
// Exit radiance of the height field: albedo times the accumulated shading (L . (V * C), which
// already holds the Lambert 1/pi), plus the material's emission. The albedo is the material's
// colour times its albedo map at the mesh uv, as the other raster methods and the reference take
// it (a 1x1 white map when the material has none, so untextured fields are unchanged).
layout(set = 0, binding = 2) uniform sampler2D shading;
layout(set = 0, binding = 3) uniform sampler2D albedo_map;

layout(push_constant) uniform Terrain {
    vec4 origin;
    vec4 albedo;
    vec4 emission;
} terrain;

layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;

void main() {
    vec3 albedo = terrain.albedo.rgb * texture(albedo_map, in_uv).rgb;
    out_radiance = vec4(albedo * texture(shading, in_uv).rgb + terrain.emission.rgb, 1.0);
}
