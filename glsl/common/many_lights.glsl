// Ridderhof 2002's light models for one light at its current intensity: the shader twin of
// src/lighting/many_lights/light_model.rs (ManyLight::shade, a diffuse point's light, which picks
// the light sets), held to it on a diffuse floor by tests/methods/vls.rs.
//   0 physical: (rho/pi + normalised Blinn-Phong lobe) * I * smoothstep cone / d^2 * cos, as
//               forward shades (common/lights.glsl)
//   1 seed:     k * rho * I * ramp / d * cos, the ramp linear in angle between the full and null cones
//   2 opengl:   rho * I * max(0, cos_axis)^e / (kc + kl d + kq d^2) * cos inside the null cone,
//               with cos(full)^e = 1/2; its ambient and specular terms: opengl_ambient_specular
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

// The fixed-function model's attenuation times its spot factor (0 outside the null cone), and
// the unit direction to the light in `l`.
float opengl_reach(vec4 constants, Light light, vec3 p, out vec3 l) {
    vec3 to_light = light.position.xyz - p;
    float dist = length(to_light);
    l = vec3(0.0);
    if (dist <= 1e-12) {
        return 0.0;
    }
    l = to_light / dist;
    float factor = 1.0;
    if (uint(light.position.w) == LIGHT_SPOT) {
        float cos_axis = dot(-l, light.direction.xyz);
        factor = cos_axis < light.cone.y ? 0.0 : pow(max(cos_axis, 0.0), opengl_spot_exponent(light.cone.x));
    }
    return factor / max(constants.y + constants.z * dist + constants.w * dist * dist, 1e-12);
}

// The fixed-function terms beside the diffuse one (Ridderhof 2002 section 4.3.1: attenuation * spot *
// (ambient + diffuse + specular)): the light's ambient, `light_ambient` times its intensity
// times the albedo (the material's ambient is its diffuse colour, as with GL_COLOR_MATERIAL),
// and Blinn-Phong specular ks * I * max(0, N.H)^shininess seen from `eye` (a local viewer),
// only where N.L > 0. `specular` is (ks, shininess).
vec3 opengl_ambient_specular(vec4 constants, float light_ambient, Light light, vec3 p, vec3 n, vec3 eye,
                             vec3 albedo, vec4 specular) {
    vec3 l;
    float reach = opengl_reach(constants, light, p, l);
    if (reach <= 0.0) {
        return vec3(0.0);
    }
    vec3 sum = light_ambient * albedo;
    if (dot(n, l) > 0.0 && any(greaterThan(specular.rgb, vec3(0.0)))) {
        vec3 h = normalize(l + normalize(eye - p));
        sum += specular.rgb * pow(max(dot(n, h), 0.0), specular.a);
    }
    return light.intensity.rgb * reach * sum;
}

// One light's direct radiance toward `eye` at p. The physical model is forward's: the material's
// Lambert + normalised Blinn-Phong BRDF (common/lights.glsl) under the inverse-square law; the
// seed's and OpenGL's models light the albedo only (OpenGL's ambient and specular terms are
// opengl_ambient_specular's). `specular` is the material's (ks, exponent).
vec3 many_light_shade(uint model, vec4 constants, Light light, vec3 p, vec3 n, vec3 eye, vec3 albedo, vec4 specular) {
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
        vec3 v = normalize(eye - p);
        return light.intensity.rgb * (factor / (dist * dist)) * brdf_times_cos(n, v, l, albedo, specular.rgb, specular.w);
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
