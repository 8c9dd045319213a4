// Virtualised light sources: what both stages read (src/lighting/vls/mod.rs). The vertex stage
// shades per vertex (point = "vertex"), the fragment stage per pixel (point = "centroid").
#ifndef PENUMBRA_VLS_GLSL
#define PENUMBRA_VLS_GLSL

#include "common/frame.glsl"
#include "common/lights.glsl"
#include "common/many_lights.glsl"

// The terms drawn (src/lighting/terms.rs): 1 base (emission + environment), 2 direct (lights).
layout(constant_id = 0) const uint TERMS = 3u;
// 1: the light sets belong to segment vertices and the direct light is shaded per vertex.
layout(constant_id = 1) const uint PER_VERTEX = 0u;

layout(set = 0, binding = 1) readonly buffer Lights { Light items[]; } lights;
// K light indices per set, 0xffffffff after the last.
layout(set = 0, binding = 2) readonly buffer Sets { uint items[]; } sets;
layout(set = 0, binding = 3) uniform VlsParams {
    uvec4 info;      // x: light model (common/many_lights.glsl), y: K
    vec4 constants;  // (k, kc, kl, kq)
    vec4 ambient;    // x: global ambient (times the albedo), y: each light's ambient; opengl only
} params;

// Thin surfaces are lit from the viewer's side, as forward shades them.
vec3 facing_normal(vec3 n, vec3 p) {
    n = normalize(n);
    return dot(n, frame.camera_pos.xyz - p) < 0.0 ? -n : n;
}

// The light of set `set`'s <= K lights at their current intensities; the fixed-function model
// adds the global ambient and each light's ambient and specular terms. `specular` is the
// material's (ks, shininess).
vec3 vls_direct(uint set, vec3 p, vec3 n, vec3 albedo, vec4 specular) {
    bool opengl = params.info.x == MODEL_OPENGL;
    vec3 sum = opengl ? params.ambient.x * albedo : vec3(0.0);
    uint k = params.info.y;
    for (uint i = 0u; i < k; ++i) {
        uint index = sets.items[set * k + i];
        if (index >= frame.counts.x) {
            break;
        }
        Light light = lights.items[index];
        sum += many_light_shade(params.info.x, params.constants, light, p, n, frame.camera_pos.xyz, albedo, specular);
        if (opengl) {
            sum += opengl_ambient_specular(params.constants, params.ambient.y, light, p, n, frame.camera_pos.xyz,
                                           albedo, specular);
        }
    }
    return sum;
}

#endif
