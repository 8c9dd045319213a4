#version 460
// The indirect term: the accumulated volume looked up at each visible surface, added into the
// radiance target over the base and direct terms.
// Corrected: trilinear (zero beyond the border) half a cell along the normal, irradiance
// E = max(0, c . coslobe(-n)) / cell^2, radiance rho/pi * E, plus for thin transmitting
// surfaces tau/pi times the irradiance arriving at the back.
// Faithful (defCompositor.glsl's GI term): albedo * clamp(SH(-n), 0, 1) at p + 0.001 of the
// volume along n, no 1/pi.
#include "common/frame.glsl"
#include "common/scene.glsl"
#define LPV_VOLUME_BINDING 1
#include "lpv/volume.glsl"

layout(constant_id = 0) const uint FAITHFUL = 0u;
// 0: the indirect term; debug views of what the look-up sees: 6 albedo, 7 shading normal,
// 8 position in the volume (the G-buffer's layers of a deferred renderer).
layout(constant_id = 1) const uint VIEW = 0u;

layout(set = 0, binding = 2) readonly buffer Materials { Material items[]; } materials;
layout(set = 0, binding = 3) uniform sampler2D albedo_map;
layout(set = 0, binding = 4) uniform sampler2D normal_map;
layout(set = 0, binding = 5) readonly buffer Transmittance { vec4 t[]; } transmittance;
layout(set = 0, binding = 6) readonly buffer Light { uint w[]; } light;

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_tangent;

layout(location = 0) out vec4 out_radiance;

// The volume at a point in cell coordinates (cell centres at integers), zero beyond the border.
void lookup(vec3 p, out vec4 c[3]) {
    vec3 base = floor(p);
    vec3 f = p - base;
    ivec3 b = ivec3(base);
    c[0] = vec4(0.0);
    c[1] = vec4(0.0);
    c[2] = vec4(0.0);
    for (int k = 0; k < 8; ++k) {
        ivec3 o = ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
        ivec3 q = b + o;
        if (!inside(q)) {
            continue;
        }
        vec3 w3 = mix(1.0 - f, f, vec3(o));
        float w = w3.x * w3.y * w3.z;
        uint cell = cell_index(q);
        for (uint ch = 0u; ch < 3u; ++ch) {
            c[ch] += w * SET_LOAD(light, slot(cell, ch));
        }
    }
}

void main() {
    Material m = materials.items[draw.material];
    vec3 v = normalize(frame.camera_pos.xyz - in_world);
    vec3 n = normalize(in_normal);
    if (dot(n, v) < 0.0) {
        n = -n;
    }
    if (m.maps.x != 0u) {
        vec3 t = normalize(in_tangent.xyz - n * dot(n, in_tangent.xyz));
        vec3 b = cross(n, t) * in_tangent.w;
        vec3 tn = texture(normal_map, in_uv).xyz * 2.0 - 1.0;
        n = normalize(t * tn.x + b * tn.y + n * tn.z);
    }
    vec3 albedo = m.albedo.rgb * texture(albedo_map, in_uv).rgb;
    float cell = volume.origin.w;
    if (VIEW != 0u) {
        vec3 inside_volume = (in_world - volume.origin.xyz) / (cell * float(volume.size.x));
        out_radiance = vec4(VIEW == 6u ? albedo : (VIEW == 7u ? n * 0.5 + 0.5 : inside_volume), 1.0);
        return;
    }
    vec4 c[3];
    vec3 radiance = vec3(0.0);
    if (FAITHFUL != 0u) {
        vec3 p = (in_world + n * (0.001 * cell * float(volume.size.x)) - volume.origin.xyz) / cell - 0.5;
        lookup(p, c);
        vec4 y = sh_basis(-n);
        for (int ch = 0; ch < 3; ++ch) {
            radiance[ch] = albedo[ch] * clamp(dot(c[ch], y), 0.0, 1.0);
        }
    } else {
        vec3 p = (in_world - volume.origin.xyz) / cell - 0.5;
        lookup(p + 0.5 * n, c);
        vec4 front = cosine_lobe(-n);
        for (int ch = 0; ch < 3; ++ch) {
            radiance[ch] = albedo[ch] * max(dot(c[ch], front), 0.0) / (cell * cell * LPV_PI);
        }
        vec3 tau = transmittance.t[draw.material].rgb;
        if (any(greaterThan(tau, vec3(0.0)))) {
            // Light reaching the back of a thin surface, looked up half a cell behind it.
            lookup(p - 0.5 * n, c);
            vec4 back = cosine_lobe(n);
            for (int ch = 0; ch < 3; ++ch) {
                radiance[ch] += tau[ch] * max(dot(c[ch], back), 0.0) / (cell * cell * LPV_PI);
            }
        }
    }
    out_radiance = vec4(radiance, 1.0);
}
