#version 460
// Forward direct lighting: emission + unshadowed environment irradiance + sum over lights of BRDF * E * cos,
// in linear radiance. Material maps are always bound (1x1 defaults when a material has none).
#include "common/frame.glsl"
#include "common/lights.glsl"
#include "common/sh.glsl"
#include "common/scene.glsl"

// The terms drawn (src/lighting/terms.rs): 1 base (emission + environment), 2 direct (lights).
layout(constant_id = 0) const uint TERMS = 3u;

layout(set = 0, binding = 1) readonly buffer Lights { Light items[]; } lights;
layout(set = 0, binding = 2) readonly buffer Materials { Material items[]; } materials;
layout(set = 0, binding = 3) uniform sampler2D albedo_map;
layout(set = 0, binding = 4) uniform sampler2D normal_map;
layout(set = 0, binding = 5) uniform sampler2D specular_map;

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_tangent;

layout(location = 0) out vec4 out_radiance;

// Unshadowed irradiance from the environment (clamped: a 3-band fit can dip below zero).
vec3 environment_irradiance(vec3 n) {
    // The unrolled 4-band evaluation; only the first 3 bands (9 coefficients) are used.
    float y[16];
    sh_eval16(sh_world_to_sh(n), y);
    vec3 e = vec3(0.0);
    for (int i = 0; i < 9; ++i) {
        e += frame.env_irradiance[i].rgb * y[i];
    }
    return max(e, vec3(0.0));
}

void main() {
    Material m = materials.items[draw.material];
    vec3 v = normalize(frame.camera_pos.xyz - in_world);
    vec3 n = normalize(in_normal);
    vec3 emission = m.emission.rgb;
    // Surfaces seen from behind: one-sided emitters don't emit there; other surfaces are thin
    // and lit from the viewer's side, so the shading frame is flipped before normal mapping
    // (deciding on the mapped normal would flip texels that merely lean away).
    if (dot(n, v) < 0.0) {
        n = -n;
        if (m.maps.y != 0u) {
            emission = vec3(0.0);
        }
    }
    if (m.maps.x != 0u) {
        // Tangent-space normal map; Gram-Schmidt keeps the frame orthonormal after interpolation.
        vec3 t = normalize(in_tangent.xyz - n * dot(n, in_tangent.xyz));
        vec3 b = cross(n, t) * in_tangent.w;
        vec3 tn = texture(normal_map, in_uv).xyz * 2.0 - 1.0;
        n = normalize(t * tn.x + b * tn.y + n * tn.z);
    }
    vec3 albedo = m.albedo.rgb * texture(albedo_map, in_uv).rgb;
    vec3 specular = m.specular.rgb * texture(specular_map, in_uv).rgb;
    vec3 radiance = vec3(0.0);
    if ((TERMS & 1u) != 0u) {
        radiance = emission + albedo / PI * environment_irradiance(n);
    }
    for (uint i = 0u; (TERMS & 2u) != 0u && i < frame.counts.x; ++i) {
        vec3 l;
        vec3 e;
        light_incidence(lights.items[i], in_world, l, e);
        radiance += brdf_times_cos(n, v, l, albedo, specular, m.specular.w) * e;
    }
    out_radiance = vec4(radiance, 1.0);
}
