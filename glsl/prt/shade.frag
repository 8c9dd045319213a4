#version 460
// Run-time PRT shading (src/lighting/prt/mod.rs): emission plus albedo / pi times the
// interpolated irradiance of shade.vert (clamped: a truncated SH reconstruction can dip below 0).
#include "common/frame.glsl"
#include "common/scene.glsl"

layout(set = 0, binding = 3) readonly buffer Materials { Material items[]; } materials;
layout(set = 0, binding = 4) uniform sampler2D albedo_map;

layout(location = 0) in vec3 in_irradiance;
layout(location = 1) in vec2 in_uv;
layout(location = 2) in vec3 in_normal;
layout(location = 3) in vec3 in_world;

layout(location = 0) out vec4 out_radiance;

void main() {
    Material m = materials.items[draw.material];
    vec3 emission = m.emission.rgb;
    vec3 v = frame.camera_pos.xyz - in_world;
    if (m.maps.y != 0u && dot(in_normal, v) < 0.0) {
        emission = vec3(0.0);
    }
    vec3 albedo = m.albedo.rgb * texture(albedo_map, in_uv).rgb;
    out_radiance = vec4(emission + albedo / 3.14159265358979 * max(in_irradiance, vec3(0.0)), 1.0);
}
