#version 460
// One RSM texel: the flux the surfel it sees reflects (rho * E_perp * texel area for the sun,
// rho * I * texel solid angle for a spot light: the N.L is in the surfel's footprint, so the
// sum over texels does not depend on the RSM's resolution), the flux it transmits, its area,
// position and normal (turned toward the light: surfaces are two-sided). Drawn from the camera
// (light.w = 2) it is the camera's G-buffer: no flux, the area of the pixel's footprint.
#include "lpv/volume.glsl"
#include "common/scene.glsl"
#include "common/lights.glsl"

layout(set = 0, binding = 1) readonly buffer Materials { Material items[]; } materials;
layout(set = 0, binding = 2) uniform sampler2D albedo_map;
layout(set = 0, binding = 3) readonly buffer Transmittance { vec4 t[]; } transmittance;

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;

layout(location = 0) out vec4 out_flux;
layout(location = 1) out vec4 out_transmitted;
layout(location = 2) out vec4 out_position;
layout(location = 3) out vec4 out_normal;

void main() {
    Material m = materials.items[draw.material];
    vec3 albedo = m.albedo.rgb * texture(albedo_map, in_uv).rgb;
    vec3 tau = transmittance.t[draw.material].rgb;
    vec3 n = normalize(in_normal);
    vec3 l;
    vec3 power;  // flux reaching this texel's surfel
    float area;  // the surfel's area
    float size = float(volume.rsm.x);
    if (volume.light.w > 1.5) {
        // The G-buffer's surfels (for the geometry volume): no flux; the area the pixel covers.
        l = normalize(in_world - volume.light_pos.xyz);
        power = vec3(0.0);
        area = length(cross(dFdx(in_world), dFdy(in_world)));
    } else if (volume.light.w < 0.5) {
        l = volume.light.xyz;
        power = volume.light_intensity.rgb * volume.light_intensity.w;
        area = volume.light_intensity.w / max(abs(dot(n, l)), 0.1);
    } else {
        vec3 d = in_world - volume.light_pos.xyz;
        float dist2 = max(dot(d, d), 1e-12);
        l = d * inversesqrt(dist2);
        vec2 ndc = gl_FragCoord.xy / size * 2.0 - 1.0;
        float t = volume.light_intensity.w;
        float texel = 2.0 * t / size;
        float omega = texel * texel / pow(1.0 + t * t * dot(ndc, ndc), 1.5);
        float falloff = spot_falloff(volume.light_cone.y, volume.light_cone.x, dot(l, volume.light.xyz));
        power = volume.light_intensity.rgb * falloff * omega;
        area = omega * dist2 / max(abs(dot(n, l)), 0.1);
    }
    if (dot(n, l) > 0.0) {
        n = -n;
    }
    if (volume.light_cone.z > 0.5) {
        // The document's RSM: the albedo, radiant flux 1.0.
        out_flux = vec4(albedo, area);
        out_transmitted = vec4(0.0, 0.0, 0.0, 1.0);
    } else {
        out_flux = vec4(albedo * power, area);
        out_transmitted = vec4(tau * power, 1.0 - (tau.r + tau.g + tau.b) / 3.0);
    }
    out_position = vec4(in_world, 1.0);
    out_normal = vec4(n, 0.0);
}
