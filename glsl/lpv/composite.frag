#version 460
// The indirect term: the accumulated volume looked up at each visible surface, added into the
// radiance target over the base and direct terms.
// Corrected: trilinear (zero beyond the border) half a cell along the normal, irradiance
// E = max(0, c . coslobe(-n)) / cell^2 (the sets hold c / cell^2), radiance rho/pi * E, plus for thin transmitting
// surfaces tau/pi times the irradiance arriving at the back.
// Faithful (defCompositor.glsl's GI and TI terms): albedo * clamp(SH(-n), 0, 1) at p + 0.001 of
// the volume along n, no 1/pi, and on translucent surfaces the TI term below.
// With cascades (nested volumes around the camera), the finest one holding the point with a
// cell to spare, blended into the next over its last two cells.
#include "common/frame.glsl"
#include "common/scene.glsl"
#define LPV_VOLUME_BINDING 1
#include "lpv/volume.glsl"

layout(constant_id = 0) const uint FAITHFUL = 0u;
// 0: the indirect term; debug views of what the look-up reads: 6 albedo, 7 shading normal,
// 8 position in the (finest) volume (the G-buffer's layers of a deferred renderer).
layout(constant_id = 1) const uint VIEW = 0u;
// The document's compositor (faithful): the look-up blended with the direct term as
// defCompositor.glsl does, D = clamp(n.toLight) * shadow; I = D + (1 - D) GI; I += (1 - I) TI;
// this pass adds albedo * (I - D), the direct method below supplying the direct light.
layout(constant_id = 2) const uint BLEND = 0u;

layout(set = 0, binding = 2) readonly buffer Materials { Material items[]; } materials;
layout(set = 0, binding = 3) uniform sampler2D albedo_map;
layout(set = 0, binding = 4) uniform sampler2D normal_map;
layout(set = 0, binding = 5) readonly buffer Transmittance { vec4 t[]; } transmittance;
layout(set = 0, binding = 6) readonly buffer Light0 { uint w[]; } light0;
layout(set = 0, binding = 7) readonly buffer Light1 { uint w[]; } light1;
layout(set = 0, binding = 8) readonly buffer Light2 { uint w[]; } light2;
layout(set = 0, binding = 9) readonly buffer Light3 { uint w[]; } light3;
layout(set = 0, binding = 10) uniform Cascades {
    uvec4 count;     // x: cascades in use
    vec4 origin[4];  // xyz: a cascade's corner; w: its cell size
} cascades;

// The RSM's position layer (xyz: the surface the light sees; w: 1 where it saw one).
layout(set = 0, binding = 11) uniform sampler2D rsm_position;

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_tangent;

layout(location = 0) out vec4 out_radiance;

vec4 load(int k, uint s) {
    if (k == 0) {
        return SET_LOAD(light0, s);
    } else if (k == 1) {
        return SET_LOAD(light1, s);
    } else if (k == 2) {
        return SET_LOAD(light2, s);
    }
    return SET_LOAD(light3, s);
}

// Cascade k at a point in its cell coordinates (cell centres at integers), zero beyond the
// border.
void lookup(int k, vec3 p, out vec4 c[3]) {
    vec3 base = floor(p);
    vec3 f = p - base;
    ivec3 b = ivec3(base);
    c[0] = vec4(0.0);
    c[1] = vec4(0.0);
    c[2] = vec4(0.0);
    for (int corner = 0; corner < 8; ++corner) {
        ivec3 o = ivec3(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        ivec3 q = b + o;
        if (!inside(q)) {
            continue;
        }
        vec3 w3 = mix(1.0 - f, f, vec3(o));
        float w = w3.x * w3.y * w3.z;
        uint cell = cell_index(q);
        for (uint ch = 0u; ch < 3u; ++ch) {
            c[ch] += w * load(k, slot(cell, ch));
        }
    }
}

// 1 where the light reaches the point, 0 where the RSM saw a surface nearer the light by more
// than half a cell (one tap: the document's 17-tap depth-difference sum is not reproduced);
// 1 outside the RSM.
float lit(vec3 l) {
    vec4 clip = volume.light_view_proj * vec4(in_world, 1.0);
    vec2 uv = clip.xy / clip.w * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThanEqual(uv, vec2(1.0)))) {
        return 1.0;
    }
    vec4 seen = texelFetch(rsm_position, ivec2(uv * float(volume.rsm.x)), 0);
    if (seen.w < 0.5) {
        return 1.0;
    }
    float nearer = volume.light.w > 0.5 ? distance(in_world, volume.light_pos.xyz) - distance(seen.xyz, volume.light_pos.xyz) : dot(seen.xyz - in_world, -l);
    return nearer > 0.5 * volume.origin.w ? 0.0 : 1.0;
}

// The indirect light cascade k gives the point.
vec3 shade(int k, vec3 n, vec3 albedo, vec3 tau) {
    float cell = cascades.origin[k].w;
    vec3 origin = cascades.origin[k].xyz;
    vec4 c[3];
    vec3 radiance = vec3(0.0);
    if (FAITHFUL != 0u) {
        vec3 p = (in_world + n * (0.001 * cell * float(volume.size.x)) - origin) / cell - 0.5;
        lookup(k, p, c);
        vec4 y = sh_basis(-n);
        vec3 l = volume.light.w > 0.5 ? normalize(in_world - volume.light_pos.xyz) : volume.light.xyz;
        float shadow = BLEND != 0u ? lit(l) : 1.0;
        float d = BLEND != 0u ? clamp(dot(n, -l), 0.0, 1.0) * shadow : 0.0;
        vec3 gi;
        for (int ch = 0; ch < 3; ++ch) {
            gi[ch] = clamp(dot(c[ch], y), 0.0, 1.0);
            // (D + (1 - D) GI) - D
            radiance[ch] = albedo[ch] * (1.0 - d) * gi[ch];
        }
        if (any(greaterThan(tau, vec3(0.0)))) {
            // The document's TI term on translucent surfaces: the volume along the light's
            // travel, (0.05 + min(2, max(n.L, 0) / max(0.1, 1 - T))) times it and the shadow
            // factor, screen-blended over D + (1 - D) GI (with `blend`; else added in full).
            float t = (tau.r + tau.g + tau.b) / 3.0;
            float back = 0.05 + min(2.0, max(dot(n, l), 0.0) / max(0.1, 1.0 - t));
            vec4 yl = sh_basis(l);
            for (int ch = 0; ch < 3; ++ch) {
                float ti = back * clamp(dot(c[ch], yl), 0.0, 1.0) * shadow;
                radiance[ch] += albedo[ch] * (BLEND != 0u ? 1.0 - (d + (1.0 - d) * gi[ch]) : 1.0) * ti;
            }
        }
        return radiance;
    }
    vec3 p = (in_world - origin) / cell - 0.5;
    lookup(k, p + 0.5 * n, c);
    vec4 front = cosine_lobe(-n);
    for (int ch = 0; ch < 3; ++ch) {
        radiance[ch] = albedo[ch] * max(dot(c[ch], front), 0.0) / SH_PI;
    }
    if (any(greaterThan(tau, vec3(0.0)))) {
        // Light reaching the back of a thin surface, looked up half a cell behind it.
        lookup(k, p - 0.5 * n, c);
        vec4 back = cosine_lobe(n);
        for (int ch = 0; ch < 3; ++ch) {
            radiance[ch] += tau[ch] * max(dot(c[ch], back), 0.0) / SH_PI;
        }
    }
    return radiance;
}

// Cells between the point and cascade k's border, less the one cell the look-up needs.
float room(int k) {
    vec3 q = (in_world - cascades.origin[k].xyz) / cascades.origin[k].w;
    float n = float(volume.size.x);
    vec3 d = min(q, vec3(n) - q) - 1.0;
    return min(d.x, min(d.y, d.z));
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
    if (VIEW != 0u) {
        vec3 inside_volume = (in_world - cascades.origin[0].xyz) / (cascades.origin[0].w * float(volume.size.x));
        out_radiance = vec4(VIEW == 6u ? albedo : (VIEW == 7u ? n * 0.5 + 0.5 : inside_volume), 1.0);
        return;
    }
    vec3 tau = transmittance.t[draw.material].rgb;
    int count = int(cascades.count.x);
    vec3 radiance = vec3(0.0);
    for (int k = 0; k < count; ++k) {
        float r = room(k);
        if (r < 0.0 && k + 1 < count) {
            continue;
        }
        radiance = shade(k, n, albedo, tau);
        if (r < 2.0 && k + 1 < count) {
            radiance = mix(shade(k + 1, n, albedo, tau), radiance, r / 2.0);
        }
        break;
    }
    out_radiance = vec4(radiance, 1.0);
}
