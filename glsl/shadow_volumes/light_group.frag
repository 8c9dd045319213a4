#version 460
// The lights of a group (up to 96) in one pass over the receivers: each light's share
// (shade.glsl, as light.frag adds one light) where its bit in the light mask is set, i.e. where
// the stencil was 0 after that light's volumes (light_mask.frag). Drawing the receivers once
// for the group instead of once a light is the point: on a large mesh the light pass costs its
// vertices, not its pixels.
// The faithful mode's tangent-space light vector is interpolated per vertex (Listing 1). It is
// linear in the light's position: dot(L - x, t) = dot(L, t) - dot(x, t), per vertex and so
// after interpolation, so it is formed here from the interpolated frame and the interpolated
// dot(x, t), dot(x, b), dot(x, n) of surface.vert; it differs from the light pass's only in
// rounding.
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
// Per pixel, light k of the group lit it when bit k % 24 of channel k / 24 is set (the channels
// hold sums of distinct powers of two below 2^24, exact in f32).
layout(set = 0, binding = 7) uniform sampler2D light_mask;
layout(set = 0, binding = 8) readonly buffer GroupLights {
    uvec4 count;  // x: the lights in the group
    SvLight items[];
} group;

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_tangent;
layout(location = 4) in vec3 in_light_ts;  // one light's (light.frag): unused here
layout(location = 5) in vec3 in_eye_ts;
layout(location = 6) in vec3 in_bitangent;
layout(location = 7) in vec3 in_world_ts;

layout(location = 0) out vec4 out_radiance;

#include "shade.glsl"

void main() {
    Material m = materials.items[draw.material];
    SvPoint p = sv_point(m, in_world, in_normal, in_tangent, in_uv, in_eye_ts);
    uvec4 bits = uvec4(texelFetch(light_mask, ivec2(gl_FragCoord.xy), 0));
    vec3 sum = vec3(0.0);
    for (uint k = 0u; k < group.count.x; ++k) {
        if (((bits[k / 24u] >> (k % 24u)) & 1u) == 0u) {
            continue;
        }
        SvLight l = group.items[k];
        vec3 light_ts = vec3(0.0);
        if (MODE == 0u) {
            vec3 at = vec3(dot(l.position.xyz, in_tangent.xyz), dot(l.position.xyz, in_bitangent), dot(l.position.xyz, in_normal));
            // A directional light's position is its direction, the same at every vertex.
            light_ts = uint(l.spot_direction.w + 0.5) == LIGHT_DIRECTIONAL ? at : at - in_world_ts;
        }
        sum += sv_shade(l, p, light_ts);
    }
    // Alpha 0: the ambient pass's alpha of 1 stays as it is under additive blending.
    out_radiance = vec4(sum, 0.0);
}
