// Seed 003's light models for one light at its current intensity: the shader twin of
// src/many_lights/light_model.rs (ManyLight::shade), held to it by tests/vls.rs.
//   0 physical: rho/pi * I * smoothstep cone / d^2 * cos (as common/lights.glsl)
//   1 seed:     k * rho * I * ramp / d * cos, the ramp linear in angle between the full and null cones
//   2 opengl:   rho * I * max(0, cos_axis)^e / (kc + kl d + kq d^2) * cos inside the null cone,
//               with cos(full)^e = 1/2
// constants = (k, kc, kl, kq). Lights come as `Light` (common/lights.glsl): cone.x = cos(full),
// cone.y = cos(null).
#ifndef PENUMBRA_MANY_LIGHTS_GLSL
#define PENUMBRA_MANY_LIGHTS_GLSL

#include "common/lights.glsl"

const uint MODEL_PHYSICAL = 0u;
const uint MODEL_SEED = 1u;
const uint MODEL_OPENGL = 2u;

float seed_spot_ramp(float full, float null_angle, float angle) {
    if (angle >= null_angle) {
        return 0.0;
    }
    if (angle <= full || null_angle - full <= 1e-12) {
        return 1.0;
    }
    return (null_angle - angle) / (null_angle - full);
}

float opengl_spot_exponent(float cos_full) {
    if (cos_full >= 1.0) {
        return 128.0;
    }
    return clamp(log(0.5) / log(cos_full), 0.0, 128.0);
}

vec3 many_light_shade(uint model, vec4 constants, Light light, vec3 p, vec3 n, vec3 albedo) {
    vec3 to_light = light.position.xyz - p;
    float dist = length(to_light);
    if (dist <= 1e-12) {
        return vec3(0.0);
    }
    vec3 l = to_light / dist;
    float cos_n = max(dot(n, l), 0.0);
    bool spot = uint(light.position.w) == LIGHT_SPOT;
    float cos_axis = dot(-l, light.direction.xyz);
    float scale;
    if (model == MODEL_PHYSICAL) {
        float factor = spot ? spot_falloff(light.cone.y, light.cone.x, cos_axis) : 1.0;
        scale = factor * cos_n / (dist * dist) / PI;
    } else if (model == MODEL_SEED) {
        float factor = spot ? seed_spot_ramp(acos(clamp(light.cone.x, -1.0, 1.0)), acos(clamp(light.cone.y, -1.0, 1.0)), acos(clamp(cos_axis, -1.0, 1.0))) : 1.0;
        scale = factor * cos_n * constants.x / dist;
    } else {
        float factor = 1.0;
        if (spot) {
            factor = cos_axis < light.cone.y ? 0.0 : pow(max(cos_axis, 0.0), opengl_spot_exponent(light.cone.x));
        }
        scale = factor * cos_n / max(constants.y + constants.z * dist + constants.w * dist * dist, 1e-12);
    }
    return albedo * light.intensity.rgb * scale;
}

#endif
