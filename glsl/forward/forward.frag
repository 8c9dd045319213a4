#version 460
// Forward direct lighting: emission + unshadowed environment irradiance + sum over lights of BRDF * E * cos,
// in linear radiance. Material maps are always bound (1x1 defaults when a material has none).
#include "common/frame.glsl"
#include "common/lights.glsl"
#include "common/sh.glsl"
#include "common/scene.glsl"
#include "common/surface.glsl"

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

void main() {
    SurfacePoint s = surface_point(materials.items[draw.material], in_world, in_normal, in_uv, in_tangent, albedo_map, normal_map, specular_map);
    vec3 radiance = vec3(0.0);
    if ((TERMS & 1u) != 0u) {
        radiance = s.emission + s.albedo / PI * environment_irradiance(s.n);
    }
    for (uint i = 0u; (TERMS & 2u) != 0u && i < frame.counts.x; ++i) {
        vec3 l;
        vec3 e;
        light_incidence(lights.items[i], in_world, l, e);
        radiance += brdf_times_cos(s.n, s.v, l, s.albedo, s.specular, s.exponent) * e;
    }
    // Alpha is the material's opacity: 1 for opaque surfaces, the blend weight for translucent
    // ones (drawn after, over what lies behind).
    out_radiance = vec4(radiance, materials.items[draw.material].albedo.w);
}
