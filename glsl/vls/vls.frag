#version 460
// Virtualised light sources (seed 003, digest section 1.4): a segment shades with only the <= K
// lights its set-up chose, at their current intensities; lights outside the set contribute
// nothing and shadows are only the set-up's feeler (a blocked light is not in the set).
#include "common/frame.glsl"
#include "common/lights.glsl"
#include "common/many_lights.glsl"
#include "common/sh.glsl"

// The terms drawn (src/lighting/terms.rs): 1 base (emission + environment), 2 direct (lights).
layout(constant_id = 0) const uint TERMS = 3u;

layout(set = 0, binding = 1) readonly buffer Lights { Light items[]; } lights;
// K light indices per segment, 0xffffffff after the last.
layout(set = 0, binding = 2) readonly buffer Sets { uint items[]; } sets;
layout(set = 0, binding = 3) uniform VlsParams {
    uvec4 info;      // x: light model (common/many_lights.glsl), y: K
    vec4 constants;  // (k, kc, kl, kq)
} params;

layout(location = 0) in vec3 in_world;
layout(location = 1) flat in vec3 in_normal;
layout(location = 2) flat in vec3 in_albedo;
layout(location = 3) flat in vec3 in_emission;
layout(location = 4) flat in uint in_segment;

layout(location = 0) out vec4 out_radiance;

// As glsl/forward/forward.frag: unshadowed environment irradiance, clamped.
vec3 environment_irradiance(vec3 n) {
    float y[16];
    sh_eval16(sh_world_to_sh(n), y);
    vec3 e = vec3(0.0);
    for (int i = 0; i < 9; ++i) {
        e += frame.env_irradiance[i].rgb * y[i];
    }
    return max(e, vec3(0.0));
}

void main() {
    vec3 n = normalize(in_normal);
    // Thin surfaces are lit from the viewer's side, as forward shades them.
    if (dot(n, frame.camera_pos.xyz - in_world) < 0.0) {
        n = -n;
    }
    vec3 radiance = vec3(0.0);
    if ((TERMS & 1u) != 0u) {
        radiance = in_emission + in_albedo / PI * environment_irradiance(n);
    }
    if ((TERMS & 2u) != 0u) {
        uint k = params.info.y;
        for (uint i = 0u; i < k; ++i) {
            uint index = sets.items[in_segment * k + i];
            if (index >= frame.counts.x) {
                break;
            }
            radiance += many_light_shade(params.info.x, params.constants, lights.items[index], in_world, n, in_albedo);
        }
    }
    out_radiance = vec4(radiance, 1.0);
}
