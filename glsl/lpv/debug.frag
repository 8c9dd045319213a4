#version 460
// Full-screen debug views of the LPV: an RSM layer (reflected or transmitted flux per unit
// area, normal, position in the volume), the volume's slices tiled across the image, each
// cell showing its flux per unit area (2 sqrt(pi) c0 / cell^2), or a layer of the camera's
// G-buffer (normal; depth: the distance from the camera, volume.light_pos, over the volume's
// side).
#include "lpv/volume.glsl"

// 1 flux, 2 transmitted, 3 normal, 4 position, 5 slices, 9 G-buffer normal, 10 G-buffer depth
layout(constant_id = 0) const uint VIEW = 1u;

layout(set = 0, binding = 1) uniform sampler2D rsm_flux;
layout(set = 0, binding = 2) uniform sampler2D rsm_layer;
layout(set = 0, binding = 3) readonly buffer Light { uint w[]; } light;

layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;

void main() {
    vec3 c = vec3(0.0);
    if (VIEW == 9u) {
        vec4 v = texture(rsm_layer, in_uv);
        c = dot(v.xyz, v.xyz) > 0.0 ? v.xyz * 0.5 + 0.5 : vec3(0.0);
    } else if (VIEW == 10u) {
        vec4 v = texture(rsm_layer, in_uv);
        float side = volume.origin.w * float(volume.size.x);
        c = v.w > 0.5 ? vec3(distance(v.xyz, volume.light_pos.xyz) / side) : vec3(0.0);
    } else if (VIEW <= 4u) {
        vec4 flux = texture(rsm_flux, in_uv);
        vec4 v = texture(rsm_layer, in_uv);
        if (VIEW == 1u || VIEW == 2u) {
            c = flux.a > 0.0 ? v.rgb / flux.a : vec3(0.0);
        } else if (VIEW == 3u) {
            c = dot(v.xyz, v.xyz) > 0.0 ? v.xyz * 0.5 + 0.5 : vec3(0.0);
        } else {
            c = v.w > 0.5 ? (v.xyz - volume.origin.xyz) / (volume.origin.w * float(volume.size.x)) : vec3(0.0);
        }
    } else {
        int n = volume.size.x;
        int tiles = int(ceil(sqrt(float(n))));
        vec2 t = in_uv * float(tiles);
        ivec2 tile = ivec2(floor(t));
        int z = tile.y * tiles + tile.x;
        if (z < n) {
            ivec2 xy = ivec2(fract(t) * float(n));
            // Slices from the volume's top (y) down, seen from above: x right, z down.
            ivec3 cell = ivec3(xy.x, n - 1 - z, xy.y);
            uint i = cell_index(cell);
            float area = volume.origin.w * volume.origin.w;
            for (uint ch = 0u; ch < 3u; ++ch) {
                c[ch] = max(SET_LOAD(light, slot(i, ch)).x, 0.0) * volume.scale.y * 2.0 * sqrt(SH_PI) / area;
            }
        }
    }
    out_radiance = vec4(c, 1.0);
}
