// One light's share at a surface point, as the light pass adds it (one light, where the stencil
// is 0) and the grouped light pass (each light of a group, where its bit in the light mask is
// set). light.frag says what the two modes compute. The including shader declares MODE,
// NORMAL_MAP, SPECULAR and ATTEN, the material maps, and the frame block.
#ifndef PENUMBRA_SV_SHADE_GLSL
#define PENUMBRA_SV_SHADE_GLSL

#include "common/lights.glsl"
#include "common/scene.glsl"

// What a point needs for any light: its position, its normals turned toward the viewer, its
// material after the maps, and the eye vector in tangent space.
struct SvPoint {
    vec3 world;
    vec3 ng;         // the geometric normal, on the interpolated normal's side
    bool back;       // seen from behind: the normals were turned
    vec3 albedo;
    vec3 specular;
    float exponent;
    float opacity;
    vec3 tn;         // the normal map's tangent-space normal (faithful)
    vec3 shading_n;  // the normal the normal map perturbs (physical)
    vec3 eye_ts;     // the interpolated tangent-space eye vector (faithful)
};

// The seed's attenuation functions (src/lighting/shadow_volumes/cpu.rs); r = 0 is an infinite
// radius.
float sv_attenuation(float d, float r) {
    if (ATTEN == 1u) {
        return clamp(2.0 / max(d, 1e-6) - 0.01, 0.0, 1.0);
    }
    if (r <= 0.0) {
        return 1.0;
    }
    float x = d / r;
    if (ATTEN == 2u) {
        return max(1.0 - x, 0.0);
    }
    if (ATTEN == 3u) {
        float a = max(1.0 - x, 0.0);
        return a * a;
    }
    return max(1.0 - x * x, 0.0);
}

// The point under the pixel, from the surface's interpolants. Textures are sampled here, before
// any branch on the light, so their derivatives are taken in uniform control flow.
SvPoint sv_point(Material m, vec3 world, vec3 normal, vec4 tangent, vec2 uv, vec3 eye_ts) {
    SvPoint p;
    p.world = world;
    vec3 n = normalize(normal);
    vec3 ng = normalize(cross(dFdx(world), dFdy(world)));
    if (dot(ng, n) < 0.0) {
        ng = -ng;
    }
    // Thin surfaces seen from behind are lit from the viewer's side, as in the forward method.
    p.back = dot(n, frame.camera_pos.xyz - world) < 0.0;
    if (p.back) {
        n = -n;
        ng = -ng;
    }
    p.ng = ng;
    p.albedo = m.albedo.rgb * texture(albedo_map, uv).rgb;
    p.specular = SPECULAR ? m.specular.rgb * texture(specular_map, uv).rgb : vec3(0.0);
    p.exponent = m.specular.w;
    p.opacity = m.albedo.w;
    p.tn = NORMAL_MAP ? normalize(texture(normal_map, uv).xyz * 2.0 - 1.0) : vec3(0.0, 0.0, 1.0);
    p.shading_n = n;
    if (NORMAL_MAP) {
        vec3 t = normalize(tangent.xyz - n * dot(n, tangent.xyz));
        vec3 b = cross(n, t) * tangent.w;
        p.shading_n = normalize(t * p.tn.x + b * p.tn.y + n * p.tn.z);
    }
    p.eye_ts = eye_ts;
    return p;
}

// Light `light`'s radiance toward the eye at `p`; `light_ts` is the interpolated tangent-space
// light vector (faithful mode only).
vec3 sv_shade(SvLight light, SvPoint p, vec3 light_ts) {
    uint kind = uint(light.spot_direction.w + 0.5);
    // A directional light: position.xyz is the unit vector toward it, at distance 1, so the
    // attenuation and 1/d^2 below are 1 and the colour is its irradiance.
    bool sun = kind == LIGHT_DIRECTIONAL;
    vec3 to_light = sun ? light.position.xyz : light.position.xyz - p.world;
    float dist = sun ? 1.0 : length(to_light);
    float radius = sun ? 0.0 : light.position.w;
    // A surface whose geometric normal faces away from the light gets nothing: it is the near
    // cap of its own shadow volume, where the stencil count is a depth tie.
    if (dot(p.ng, to_light) <= 0.0) {
        return vec3(0.0);
    }
    // Exactly 1 inside the inner cone, so a spot light there is bit-identical to a point light.
    float spot = 1.0;
    if (kind == LIGHT_SPOT) {
        spot = spot_falloff(light.cone.y, light.cone.x, dot(-to_light / max(dist, 1e-12), light.spot_direction.xyz));
        if (spot <= 0.0) {
            return vec3(0.0);
        }
    }
    if (MODE == 0u) {
        // Seen from behind, the frame is (t, -b, -n), as the forward method flips it.
        vec3 flip = p.back ? vec3(1.0, -1.0, -1.0) : vec3(1.0);
        vec3 l = normalize(light_ts) * flip;
        vec3 e = normalize(p.eye_ts) * flip;
        float diff = clamp(dot(p.tn, l), 0.0, 1.0);
        vec3 c = diff * p.albedo;
        if (SPECULAR) {
            float spec = diff > 0.0 ? clamp(dot(p.tn, normalize(l + e)), 0.0, 1.0) : 0.0;
            c += pow(spec, 32.0) * p.specular;
        }
        return spot * sv_attenuation(dist, radius) * light.colour.rgb * c * p.opacity;
    }
    if (radius > 0.0 && dist > radius) {
        return vec3(0.0);
    }
    vec3 v = normalize(frame.camera_pos.xyz - p.world);
    return spot * brdf_times_cos(p.shading_n, v, to_light / dist, p.albedo, p.specular, p.exponent) * light.colour.rgb / (dist * dist) * p.opacity;
}

#endif
