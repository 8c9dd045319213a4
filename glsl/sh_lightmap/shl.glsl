// Shared by the native and compressed SH light-map shaders (the Ca3D-Engine thesis listings 2-5): the light's
// coefficients, the specialisation constants, and shading a texel's transfer.
#include "common/frame.glsl"
#include "common/scene.glsl"

layout(set = 0, binding = 1) readonly buffer Materials { Material items[]; } materials;
layout(set = 0, binding = 2) uniform sampler2D albedo_map;
layout(set = 0, binding = 4) uniform sampler2D normal_map;

// Per channel, 16 vec4 groups of radiance coefficients (faithful: the luminance in channel 0).
layout(set = 0, binding = 5) uniform Light { vec4 coeffs[48]; } light;
// An environment image's radiance coefficients (RGB per coefficient), projected on the device
// every frame; zeros without one.
layout(set = 0, binding = 7) readonly buffer EnvSh { vec4 items[]; } env_sh;

layout(constant_id = 0) const int BANDS = 4;
// The coefficients are the seed's 8-bit range encoding, decoded as 4 (t - 1/2).
layout(constant_id = 1) const bool ENCODED = true;
// The Ca3D-Engine thesis's monochrome shading, clamp(sum, 0, 1) x diffuse; else RGB light, max(sum, 0).
layout(constant_id = 2) const bool FAITHFUL = true;
// 0 final, 1 the first layer as RGB, 2 the index map, 3 bare SHL without the diffuse colour.
layout(constant_id = 3) const int VIEW = 0;
layout(constant_id = 4) const bool FILTER = false;

const int GROUPS = (BANDS * BANDS + 3) / 4;

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_lightmap_uv;
layout(location = 3) in vec2 in_uv;

layout(location = 0) out vec4 out_radiance;

vec4 decode(vec4 t) {
    return ENCODED ? 4.0 * (t - 0.5) : t;
}

// One group of 4 coefficients against the light: RGB (channel 0, the luminance, when faithful).
vec3 shade_group(vec4 t, int k) {
    vec3 e0 = env_sh.items[4 * k].rgb, e1 = env_sh.items[4 * k + 1].rgb, e2 = env_sh.items[4 * k + 2].rgb, e3 = env_sh.items[4 * k + 3].rgb;
    if (FAITHFUL) {
        const vec3 Y = vec3(0.2126, 0.7152, 0.0722);
        return vec3(dot(t, light.coeffs[k] + vec4(dot(e0, Y), dot(e1, Y), dot(e2, Y), dot(e3, Y))));
    }
    vec3 env = vec3(dot(t, vec4(e0.r, e1.r, e2.r, e3.r)), dot(t, vec4(e0.g, e1.g, e2.g, e3.g)), dot(t, vec4(e0.b, e1.b, e2.b, e3.b)));
    return env + vec3(dot(t, light.coeffs[k]), dot(t, light.coeffs[16 + k]), dot(t, light.coeffs[32 + k]));
}

// The frame's radiance from the light reflected (sum of the groups) and the material.
void finish(vec3 shl, vec3 first_layer, vec3 index_colour) {
    Material m = materials.items[draw.material];
    vec3 emission = m.emission.rgb;
    if (m.maps.y != 0u && dot(in_normal, frame.camera_pos.xyz - in_world) < 0.0) {
        emission = vec3(0.0);
    }
    vec3 light_value = FAITHFUL ? clamp(shl, 0.0, 1.0) : max(shl, vec3(0.0));
    // Entities (animated objects) have no light-map: a negative coordinate.
    if (in_lightmap_uv.x < 0.0) {
        light_value = vec3(0.0);
    }
    vec3 albedo = m.albedo.rgb * texture(albedo_map, in_uv).rgb;
    if (VIEW == 1) {
        out_radiance = vec4(first_layer, 1.0);
    } else if (VIEW == 2) {
        out_radiance = vec4(index_colour, 1.0);
    } else if (VIEW == 3) {
        out_radiance = vec4(light_value, 1.0);
    } else {
        out_radiance = vec4(emission + albedo * light_value, 1.0);
    }
}
