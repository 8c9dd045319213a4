#version 460
// The BSP shadow system's segments: the base term as forward draws it (emission + unshadowed
// environment irradiance, the material's mean albedo) and the baked, relit direct term.
#include "common/frame.glsl"
#include "common/sh.glsl"
#include "common/environment.glsl"

// The terms drawn (src/lighting/terms.rs): 1 base, 2 direct.
layout(constant_id = 0) const uint TERMS = 3u;

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec3 in_albedo;
layout(location = 3) in vec3 in_emission;
layout(location = 4) in vec3 in_direct;
layout(location = 5) in vec3 in_direct_back;

layout(location = 0) out vec4 out_radiance;

void main() {
    vec3 n = normalize(in_normal);
    // Thin surfaces take the environment and the direct light of the side the viewer sees, as
    // forward does.
    bool back = dot(n, frame.camera_pos.xyz - in_world) < 0.0;
    if (back) {
        n = -n;
    }
    vec3 radiance = vec3(0.0);
    if ((TERMS & 1u) != 0u) {
        radiance = in_emission + in_albedo / SH_PI * environment_irradiance(n);
    }
    if ((TERMS & 2u) != 0u) {
        radiance += back ? in_direct_back : in_direct;
    }
    out_radiance = vec4(radiance, 1.0);
}
