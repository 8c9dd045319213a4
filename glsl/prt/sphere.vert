#version 460
// Listing 2.3's colour-coded unit sphere (src/lighting/prt/raster.rs, faithful directions):
// drawn around every vertex of a batch through the same hemisphere projection as the occluders,
// its colour (R = phi / 2 pi, G = theta / pi of the SH frame) tells the multiplicative stage each
// pixel's direction, which then looks the basis up in the 32 x 64 textures of Listing 2.2.

#include "prt/mapping.glsl"

layout(constant_id = 0) const int MAPPING = 0;
layout(constant_id = 2) const int TILE = 32;
layout(constant_id = 3) const int TILES_PER_ROW = 32;
layout(constant_id = 4) const int BATCH = 1024;
layout(constant_id = 5) const int ATLAS_W = 1024;
layout(constant_id = 6) const int ATLAS_H = 1024;

layout(location = 0) in vec3 in_direction;  // world space, unit
layout(location = 1) in vec2 in_colour;     // phi / 2 pi, theta / pi

layout(set = 0, binding = 0) readonly buffer Receivers { PrtReceiver items[]; } receivers;

layout(location = 0) out vec2 out_colour;
layout(location = 1) out float out_front;
layout(location = 2) flat out ivec2 out_tile;

void main() {
    int slot = gl_InstanceIndex % BATCH;
    ivec2 tile = ivec2(slot % TILES_PER_ROW, slot / TILES_PER_ROW) * TILE;
    PrtReceiver r = receivers.items[gl_InstanceIndex];
    vec3 l = vec3(dot(in_direction, r.tangent.xyz), dot(in_direction, r.bitangent.xyz), dot(in_direction, r.normal.xyz));
    vec2 st = prt_project(MAPPING, normalize(l));
    vec2 pixel = vec2(tile) + (st + 1.0) * 0.5 * float(TILE);
    // The sphere only carries angles: no depth, never clipped by near and far.
    gl_Position = vec4(pixel.x / float(ATLAS_W) * 2.0 - 1.0, pixel.y / float(ATLAS_H) * 2.0 - 1.0, 0.5, 1.0);
    out_colour = in_colour;
    out_front = l.z;
    out_tile = tile;
}
