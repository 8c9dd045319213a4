#version 460
// Clustered pass 3: the scene's surfaces shaded like the forward method (emission + unshadowed
// environment irradiance + BRDF * E * cos per light), but each fragment sums only the lights
// assigned to its cluster, and each of those only within its range.
#include "common/frame.glsl"
#include "common/lights.glsl"
#include "common/sh.glsl"
#include "common/scene.glsl"
#include "common/surface.glsl"
#define CLUSTERS_BINDING 6
#include "clustered/clusters.glsl"

// The terms drawn (src/lighting/terms.rs): 1 base (emission + environment), 2 direct (lights).
layout(constant_id = 0) const uint TERMS = 3u;

layout(set = 0, binding = 1) readonly buffer Lights { Light items[]; } lights;
layout(set = 0, binding = 2) readonly buffer Materials { Material items[]; } materials;
layout(set = 0, binding = 3) uniform sampler2D albedo_map;
layout(set = 0, binding = 4) uniform sampler2D normal_map;
layout(set = 0, binding = 5) uniform sampler2D specular_map;
layout(set = 0, binding = 7) readonly buffer Volumes { LightVolume items[]; } volumes;
layout(set = 0, binding = 8) readonly buffer Counts { uint n[]; } counts;
layout(set = 0, binding = 9) readonly buffer Indices { uint i[]; } indices;

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
    if ((TERMS & 2u) != 0u) {
        // gl_FragCoord.w is 1 / clip w, and clip w is the view depth.
        uint c = cluster_at(gl_FragCoord.xy, 1.0 / gl_FragCoord.w);
        uint cap = clusters.grid.w;
        uint n = min(counts.n[c], cap);
        for (uint j = 0u; j < n; ++j) {
            uint i = indices.i[c * cap + j];
            Light light = lights.items[i];
            // The range is a hard window, the same whichever cluster the fragment falls in.
            float r = volumes.items[i].range.x;
            vec3 d = light.position.xyz - in_world;
            if (uint(light.position.w) != LIGHT_DIRECTIONAL && dot(d, d) > r * r) {
                continue;
            }
            vec3 l;
            vec3 e;
            light_incidence(light, in_world, l, e);
            radiance += brdf_times_cos(s.n, s.v, l, s.albedo, s.specular, s.exponent) * e;
        }
    }
    out_radiance = vec4(radiance, 1.0);
}
