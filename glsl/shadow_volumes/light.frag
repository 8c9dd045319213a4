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
// near cap of its own shadow volume, where the stencil count is a depth tie.
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

layout(location = 0) out vec4 out_radiance;

// The seed's attenuation functions (src/shadow_volumes/cpu.rs); r = 0 is an infinite radius.
float attenuation(float d, float r) {
    if (ATTEN == 1u) {
        return clamp(2.0 / max(d, 1e-6) - 0.01, 0.0, 1.0);
    }
    if (r <= 0.0) {
        return 1.0;
    }
    float x = d / r;
    if (ATTEN == 2u) {
        return max(1.0 - x, 0.0);
    }
    if (ATTEN == 3u) {
        float a = max(1.0 - x, 0.0);
        return a * a;
    }
    return max(1.0 - x * x, 0.0);
}

void main() {
    // Alpha 0: the ambient pass's alpha of 1 stays as it is under additive blending.
    out_radiance = vec4(0.0);
    Material m = materials.items[draw.material];
    // A directional light: position.xyz is the unit vector toward it, at distance 1, so the
    // attenuation and 1/d^2 below are 1 and the colour is its irradiance.
    bool sun = light_kind() == LIGHT_DIRECTIONAL;
    vec3 to_light = sun ? light.position.xyz : light.position.xyz - in_world;
    float dist = sun ? 1.0 : length(to_light);
    float radius = sun ? 0.0 : light.position.w;
    vec3 n = normalize(in_normal);
    vec3 ng = normalize(cross(dFdx(in_world), dFdy(in_world)));
    if (dot(ng, n) < 0.0) {
        ng = -ng;
    }
    // Thin surfaces seen from behind are lit from the viewer's side, as in the forward method.
    bool back = dot(n, frame.camera_pos.xyz - in_world) < 0.0;
    if (back) {
        n = -n;
        ng = -ng;
    }
    if (dot(ng, to_light) <= 0.0) {
        return;
    }
    // Exactly 1 inside the inner cone, so a spot light there is bit-identical to a point light.
    float spot = 1.0;
    if (light_kind() == LIGHT_SPOT) {
        spot = spot_falloff(light.cone.y, light.cone.x, dot(-to_light / max(dist, 1e-12), light.spot_direction.xyz));
        if (spot <= 0.0) {
            return;
        }
    }
    vec3 albedo = m.albedo.rgb * texture(albedo_map, in_uv).rgb;
    vec3 specular = SPECULAR ? m.specular.rgb * texture(specular_map, in_uv).rgb : vec3(0.0);
    vec3 tn = NORMAL_MAP ? normalize(texture(normal_map, in_uv).xyz * 2.0 - 1.0) : vec3(0.0, 0.0, 1.0);
    if (MODE == 0u) {
        // Seen from behind, the frame is (t, -b, -n), as the forward method flips it.
        vec3 flip = back ? vec3(1.0, -1.0, -1.0) : vec3(1.0);
        vec3 l = normalize(in_light_ts) * flip;
        vec3 e = normalize(in_eye_ts) * flip;
        float diff = clamp(dot(tn, l), 0.0, 1.0);
        vec3 c = diff * albedo;
        if (SPECULAR) {
            float spec = diff > 0.0 ? clamp(dot(tn, normalize(l + e)), 0.0, 1.0) : 0.0;
            c += pow(spec, 32.0) * specular;
        }
        out_radiance.rgb = spot * attenuation(dist, radius) * light.colour.rgb * c * m.albedo.w;
        return;
    }
    if (radius > 0.0 && dist > radius) {
        return;
    }
    if (NORMAL_MAP) {
        vec3 t = normalize(in_tangent.xyz - n * dot(n, in_tangent.xyz));
        vec3 b = cross(n, t) * in_tangent.w;
        n = normalize(t * tn.x + b * tn.y + n * tn.z);
    }
    vec3 v = normalize(frame.camera_pos.xyz - in_world);
    out_radiance.rgb = spot * brdf_times_cos(n, v, to_light / dist, albedo, specular, m.specular.w) * light.colour.rgb / (dist * dist) * m.albedo.w;
}
