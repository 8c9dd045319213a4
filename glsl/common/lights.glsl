// Punctual lights in radiometric units and the energy-normalised Lambert + Blinn-Phong BRDF.
// Matches `GpuLight` in src/gpu_scene/mod.rs and the CPU evaluation in src/lighting/brdf.rs.
#ifndef PENUMBRA_LIGHTS_GLSL
#define PENUMBRA_LIGHTS_GLSL

const float PI = 3.14159265358979323846;
const uint LIGHT_POINT = 0u;
const uint LIGHT_SPOT = 1u;
const uint LIGHT_DIRECTIONAL = 2u;
const uint LIGHT_QUAD_FAR = 3u;  // emissive quad as a point: intensity L*A*cos(theta_e)

struct Light {
    vec4 position;   // xyz position (point, spot); w: type
    vec4 direction;  // xyz: direction the light travels (spot, directional) or the quad's normal
    vec4 intensity;  // rgb: intensity W/sr (point, spot) or irradiance W/m^2 (directional)
    vec4 cone;       // x: cos(inner), y: cos(outer) (spot)
};

// Smooth from the outer cone (0) to the inner cone (1); a hard edge when they coincide, where
// smoothstep's result is undefined.
float spot_falloff(float cos_outer, float cos_inner, float cos_angle) {
    if (cos_inner - cos_outer <= 1e-7) {
        return cos_angle >= cos_outer ? 1.0 : 0.0;
    }
    return smoothstep(cos_outer, cos_inner, cos_angle);
}

// Irradiance at normal incidence arriving at `p` and the unit vector towards the light.
void light_incidence(Light light, vec3 p, out vec3 to_light, out vec3 irradiance) {
    uint type = uint(light.position.w);
    if (type == LIGHT_DIRECTIONAL) {
        to_light = -light.direction.xyz;
        irradiance = light.intensity.rgb;
        return;
    }
    vec3 d = light.position.xyz - p;
    float dist2 = max(dot(d, d), 1e-12);
    to_light = d * inversesqrt(dist2);
    irradiance = light.intensity.rgb / dist2;
    if (type == LIGHT_SPOT) {
        float cos_angle = dot(-to_light, light.direction.xyz);
        irradiance *= spot_falloff(light.cone.y, light.cone.x, cos_angle);
    } else if (type == LIGHT_QUAD_FAR) {
        irradiance *= max(dot(-to_light, light.direction.xyz), 0.0);
    }
}

// Lambert rho/pi plus energy-normalised Blinn-Phong ks (n+8)/(8 pi) (N.H)^n, the specular lobe
// only where the light is above the surface.
vec3 brdf_times_cos(vec3 n, vec3 v, vec3 l, vec3 albedo, vec3 specular, float exponent) {
    float n_dot_l = dot(n, l);
    if (n_dot_l <= 0.0) {
        return vec3(0.0);
    }
    vec3 h = normalize(l + v);
    float n_dot_h = max(dot(n, h), 0.0);
    vec3 f = albedo / PI + specular * ((exponent + 8.0) / (8.0 * PI)) * pow(n_dot_h, exponent);
    return f * n_dot_l;
}

#endif
