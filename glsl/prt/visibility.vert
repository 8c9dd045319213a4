#version 460
// Phase 1 of Staniszewski 2005's baker (src/lighting/prt/raster.rs): the occluders seen from every
// vertex of a batch, one instance per vertex, each into its tile of the visibility atlas through
// the nonlinear hemisphere projection, applied per vertex (Listing 2.4; straight edges between
// projected corners, the document's known distortion). w = 1, so depth is linear in the chosen
// metric: planar (along the normal) or radial (distance from the vertex).
//
// Planar depth (the document's path): three vertices per triangle, each its corner; what lies
// behind the vertex is cut where the depth interpolated between projected corners crosses
// zero. Radial depth: six vertices per triangle, each reading the triangle whole and clipping
// it to the hemisphere in 3D (a polygon of up to four corners, drawn as a fan of two
// triangles): a corner behind the vertex would otherwise project into the disk as its mirror
// image, and a triangle crossing the tangent plane would cover a wedge from there instead of
// ending at the rim. Clipping costs the vertex stage about six times the work.

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

layout(set = 0, binding = 0) readonly buffer Receivers { PrtReceiver items[]; } receivers;
layout(set = 0, binding = 1) readonly buffer Triangles { vec4 items[]; } triangles;  // corners, world space

layout(location = 0) out float out_front;  // depth along the normal: < 0 behind the vertex
layout(location = 1) flat out ivec2 out_tile;  // the tile's first pixel

// The fan's corner of each of the six vertices: (0, 1, 2) and (0, 2, 3).
const int FAN[6] = int[6](0, 1, 2, 0, 2, 3);

// A world point in the vertex camera's frame.
vec3 to_frame(PrtReceiver r, vec3 world) {
    vec3 e = world - r.position.xyz;
    return vec3(dot(e, r.tangent.xyz), dot(e, r.bitangent.xyz), dot(e, r.normal.xyz));
}

// Corner `corner` (0 .. 5) of the fan of triangle `tri` clipped to z >= eps (Sutherland-Hodgman:
// 0, 3 or 4 corners). Vertices past the polygon's fan sit on its first corner: nothing drawn.
vec3 clipped_corner(PrtReceiver r, int tri, int corner) {
    vec3 l[3];
    for (int k = 0; k < 3; ++k) {
        l[k] = to_frame(r, triangles.items[3 * tri + k].xyz);
    }
    float eps = max(NEAR * 0.01, 1e-7);
    vec3 poly[4] = vec3[4](l[0], l[0], l[0], l[0]);
    int n = 0;
    for (int k = 0; k < 3; ++k) {
        vec3 a = l[k];
        vec3 b = l[(k + 1) % 3];
        bool a_in = a.z >= eps;
        bool b_in = b.z >= eps;
        if (a_in) {
            poly[n++] = a;
        }
        if (a_in != b_in) {
            poly[n++] = mix(a, b, (eps - a.z) / (b.z - a.z));
        }
    }
    return (corner < 3 || n == 4) && n >= 3 ? poly[FAN[corner]] : poly[0];
}

void main() {
    // Batches start at multiples of BATCH, so the tile is the instance's place in its batch.
    int slot = gl_InstanceIndex % BATCH;
    ivec2 tile = ivec2(slot % TILES_PER_ROW, slot / TILES_PER_ROW) * TILE;
    PrtReceiver r = receivers.items[gl_InstanceIndex];
    vec3 p;
    if (RADIAL == 1) {
        p = clipped_corner(r, gl_VertexIndex / 6, gl_VertexIndex % 6);
    } else {
        p = to_frame(r, triangles.items[gl_VertexIndex].xyz);
    }
    float len = length(p);
    // A corner at the vertex itself has no direction: put it just behind, where it clips.
    vec3 d = len > 1e-12 ? p / len : vec3(0.0, 0.0, -1.0);
    vec2 st = prt_project(MAPPING, d);
    vec2 pixel = vec2(tile) + (st + 1.0) * 0.5 * float(TILE);
    float metric = RADIAL == 1 ? len : p.z;
    // Vulkan keeps 0 <= z <= 1: near and far clip, the depth test keeps the nearest occluder.
    float z = (metric - NEAR) / (FAR - NEAR);
    gl_Position = vec4(pixel.x / float(ATLAS_W) * 2.0 - 1.0, pixel.y / float(ATLAS_H) * 2.0 - 1.0, z, 1.0);
    out_front = p.z;
    out_tile = tile;
}
