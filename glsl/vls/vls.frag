#version 460
// Virtualised light sources (Ridderhof 2002, digest section 1.4): a segment shades with only the <= K
// lights its set-up chose, at their current intensities; lights outside the set contribute
// nothing and shadows are only the set-up's feeler (a blocked light is not in the set).
#include "vls/vls.glsl"
#include "common/sh.glsl"
#include "common/environment.glsl"

layout(location = 0) in vec3 in_world;
layout(location = 1) flat in vec3 in_normal;
layout(location = 2) flat in vec3 in_albedo;
layout(location = 3) flat in vec3 in_emission;
layout(location = 4) flat in uint in_set;
layout(location = 5) in vec3 in_direct;
layout(location = 6) flat in vec4 in_specular;

layout(location = 0) out vec4 out_radiance;

void main() {
    vec3 n = facing_normal(in_normal, in_world);
    vec3 radiance = vec3(0.0);
    if ((TERMS & 1u) != 0u) {
        radiance = in_emission + in_albedo / PI * environment_irradiance(n);
    }
    if ((TERMS & 2u) != 0u) {
        radiance += PER_VERTEX != 0u ? in_direct : vls_direct(in_set, in_world, n, in_albedo, in_specular);
    }
    out_radiance = vec4(radiance, 1.0);
}
