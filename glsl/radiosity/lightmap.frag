#version 460
// The Ca3D-Engine thesis's light-mapped surface: emission + albedo x albedo map x light-map, where the
// light-map holds the baked irradiance / pi (linear, bilinear, clamped, no mips). Entities get
// their emission only: the seed's dynamic objects receive no light-map light.
#include "common/frame.glsl"
#include "common/scene.glsl"

layout(set = 0, binding = 1) readonly buffer Materials { Material items[]; } materials;
layout(set = 0, binding = 2) uniform sampler2D albedo_map;
layout(set = 0, binding = 3) uniform sampler2D lightmap;
layout(set = 0, binding = 4) uniform sampler2D normal_map;

// The Ca3D-Engine thesis's ambient term: the light-map times N_z, the z of the tangent-space normal-map normal,
// as if the ambient light came from straight above the surface (digest 1.3; a material without
// a normal map reads the flat default, N_z = 1).
layout(constant_id = 0) const bool AMBIENT_NZ = false;

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_lightmap_uv;
layout(location = 3) in vec2 in_uv;

layout(location = 0) out vec4 out_radiance;

void main() {
    Material m = materials.items[draw.material];
    vec3 emission = m.emission.rgb;
    // Seen from behind (the triangle's own normal), a one-sided emitter is dark.
    if (m.maps.y != 0u && dot(in_normal, frame.camera_pos.xyz - in_world) < 0.0) {
        emission = vec3(0.0);
    }
    vec3 albedo = m.albedo.rgb * texture(albedo_map, in_uv).rgb;
    // Entities (animated objects) have no light-map: a negative coordinate.
    vec3 light = in_lightmap_uv.x < 0.0 ? vec3(0.0) : texture(lightmap, in_lightmap_uv).rgb;
    if (AMBIENT_NZ) {
        light *= max(normalize(texture(normal_map, in_uv).xyz * 2.0 - 1.0).z, 0.0);
    }
    out_radiance = vec4(emission + albedo * light, 1.0);
}
