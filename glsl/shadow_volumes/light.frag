#version 460
// One point, spot or directional light's additive pass where the stencil is 0 (outside every
// shadow volume).
// A spot light is a point light times the forward method's spot_falloff (common/lights.glsl), in
// both modes; the seed has no spot lights, so in the faithful mode this is an extension.
// faithful: Listing 1 / Eq. 5: atten(d) * L_C * (diffuse * N.L + specular * (N.H)^32), the
//   specular gated on N.L > 0, N from the normal map, L and E in tangent space, d from the
//   world-space light vector (the seed's two light vectors, never collapsed).
// physical: the renderer's BRDF (glsl/common/lights.glsl) * I / d^2 * cos, zero beyond the radius;
//   a directional light's BRDF * E * cos, as the forward method's.
// A translucent surface's light is scaled by its opacity (its share of the pixel), last, so an
// opaque one (x * 1.0) is unchanged to the bit.
// Either way a surface whose geometric normal faces away from the light gets nothing: it is the
// near cap of its own shadow volume, where the stencil count is a depth tie (shade.glsl, which
// light_group.frag shares).
#include "common/frame.glsl"
#include "common/lights.glsl"
#include "surface.glsl"

layout(constant_id = 0) const uint MODE = 0u;           // 0: faithful, 1: physical
layout(constant_id = 1) const bool NORMAL_MAP = false;  // sample and apply the normal map
layout(constant_id = 2) const bool SPECULAR = false;    // evaluate the specular term
layout(constant_id = 4) const uint ATTEN = 4u;          // attenuation function 1-4

layout(set = 0, binding = 2) readonly buffer Materials { Material items[]; } materials;
layout(set = 0, binding = 3) uniform sampler2D albedo_map;
layout(set = 0, binding = 4) uniform sampler2D normal_map;
layout(set = 0, binding = 5) uniform sampler2D specular_map;

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_tangent;
layout(location = 4) in vec3 in_light_ts;
layout(location = 5) in vec3 in_eye_ts;
layout(location = 6) in vec3 in_bitangent;  // for the grouped light pass (surface.vert)
layout(location = 7) in vec3 in_world_ts;

layout(location = 0) out vec4 out_radiance;

#include "shade.glsl"

void main() {
    // Alpha 0: the ambient pass's alpha of 1 stays as it is under additive blending.
    Material m = materials.items[draw.material];
    SvPoint p = sv_point(m, in_world, in_normal, in_tangent, in_uv, in_eye_ts);
    SvLight l = SvLight(light.position, light.colour, light.spot_direction, light.cone);
    out_radiance = vec4(sv_shade(l, p, in_light_ts), 0.0);
}
