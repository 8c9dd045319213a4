#version 460
// The ambient/emissive pass of Eq. 5: diffuse * lightmap * N_z + luminance (faithful), or the
// emission alone (physical: direct light only). Writes depth for the stencil and light passes.
// Alpha is the opacity: the opaque pipelines do not blend (alpha 1 stays 1), the translucent
// path's blend it over the opaque image.
#include "common/frame.glsl"
#include "surface.glsl"

layout(constant_id = 0) const uint MODE = 0u;           // 0: faithful, 1: physical
layout(constant_id = 1) const bool NORMAL_MAP = false;  // the material has a normal map
layout(constant_id = 3) const bool AMBIENT_NZ = true;   // scale the ambient term by N_z

layout(set = 0, binding = 2) readonly buffer Materials { Material items[]; } materials;
layout(set = 0, binding = 3) uniform sampler2D albedo_map;
layout(set = 0, binding = 4) uniform sampler2D normal_map;
layout(set = 0, binding = 6) uniform AmbientBlock {
    vec4 lightmap;  // rgb: the light-map value (a constant here; the radiosity bake is elsewhere)
} ambient;

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_tangent;
layout(location = 4) in vec3 in_light_ts;
layout(location = 5) in vec3 in_eye_ts;
layout(location = 6) in vec3 in_bitangent;  // for the grouped light pass (surface.vert)
layout(location = 7) in vec3 in_world_ts;

layout(location = 0) out vec4 out_radiance;

void main() {
    Material m = materials.items[draw.material];
    vec3 emission = m.emission.rgb;
    if (MODE == 1u) {
        out_radiance = vec4(emission, m.albedo.w);
        return;
    }
    vec3 albedo = m.albedo.rgb * texture(albedo_map, in_uv).rgb;
    float nz = 1.0;
    if (NORMAL_MAP && AMBIENT_NZ) {
        nz = normalize(texture(normal_map, in_uv).xyz * 2.0 - 1.0).z;
    }
    out_radiance = vec4(albedo * ambient.lightmap.rgb * nz + emission, m.albedo.w);
}
