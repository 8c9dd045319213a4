#version 460
// Phase 1 of Staniszewski 2005's baker (src/lighting/prt/raster.rs): the occluders seen from every
// vertex of a batch, one instance per vertex, each into its tile of the visibility atlas through
// the nonlinear hemisphere projection, applied per vertex (Listing 2.4; straight edges between
// projected corners, the document's known distortion). w = 1, so depth is linear in the chosen
// metric: planar (along the normal) or radial (distance from the vertex).

#include "prt/mapping.glsl"

layout(constant_id = 0) const int MAPPING = 0;
layout(constant_id = 1) const int RADIAL = 0;
layout(constant_id = 2) const int TILE = 32;
layout(constant_id = 3) const int TILES_PER_ROW = 32;
layout(constant_id = 4) const int BATCH = 1024;
layout(constant_id = 5) const int ATLAS_W = 1024;
layout(constant_id = 6) const int ATLAS_H = 1024;
layout(constant_id = 7) const float NEAR = 0.001;
layout(constant_id = 8) const float FAR = 1000.0;

layout(location = 0) in vec3 in_position;  // world space

layout(set = 0, binding = 0) readonly buffer Receivers { PrtReceiver items[]; } receivers;

layout(location = 0) out float out_front;  // depth along the normal: < 0 behind the vertex
layout(location = 1) flat out ivec2 out_tile;  // the tile's first pixel

void main() {
    // Batches start at multiples of BATCH, so the tile is the instance's place in its batch.
    int slot = gl_InstanceIndex % BATCH;
    ivec2 tile = ivec2(slot % TILES_PER_ROW, slot / TILES_PER_ROW) * TILE;
    PrtReceiver r = receivers.items[gl_InstanceIndex];
    vec3 e = in_position - r.position.xyz;
    vec3 l = vec3(dot(e, r.tangent.xyz), dot(e, r.bitangent.xyz), dot(e, r.normal.xyz));
    float len = length(l);
    // A corner at the vertex itself has no direction: put it just behind, where it clips.
    vec3 d = len > 1e-12 ? l / len : vec3(0.0, 0.0, -1.0);
    vec2 st = prt_project(MAPPING, d);
    vec2 pixel = vec2(tile) + (st + 1.0) * 0.5 * float(TILE);
    float metric = RADIAL == 1 ? len : l.z;
    // Vulkan keeps 0 <= z <= 1: near and far clip, the depth test keeps the nearest occluder.
    float z = (metric - NEAR) / (FAR - NEAR);
    gl_Position = vec4(pixel.x / float(ATLAS_W) * 2.0 - 1.0, pixel.y / float(ATLAS_H) * 2.0 - 1.0, z, 1.0);
    out_front = l.z;
    out_tile = tile;
}
