#version 460
// Entity shadow volumes for one light (the frame passes one light at a time, into one buffer),
// from edge adjacency, in two dispatches: one invocation per triangle (its facing, kept for the
// edges, and its near and far cap), then one per edge (its sides, from its triangles' facings). A closed mesh casts from its dark triangles (facing away from the light), and an edge
// gets a side quad if it is a silhouette edge: one adjacent triangle lit, the other dark. An
// open mesh casts from both sides: every triangle is turned to face away from the light and
// capped, and an edge gets each triangle's side unless the two turned triangles run it opposite
// ways, where the sides would cancel (so a flat sheet's volume has sides only on its border, and
// no coincident pairs inside). A light is homogeneous: (position, 1), or for a directional light
// (toward it, 0), whose volumes all run to one point at infinity, so their far caps are
// degenerate and draw nothing.
// Output is compacted: an invocation with something to draw reserves its vertices with an atomic
// add on the count of one of two indirect draws, sides (from vertex 0) or caps (from caps_base),
// so nothing is written or drawn for the many edges that are not silhouettes, or for a
// directional light's degenerate triangles. (Leaving out the triangles the view clips away
// whole cost the pass more than it saved the draws on a 269k-triangle scene.) The order within
// a draw then varies from frame to frame; with wrapping stencil operations it changes no count,
// and sides still come before caps for the saturating negative control.
// CPU mirror: silhouette_volume in src/lighting/shadow_volumes/volumes.rs.
layout(local_size_x = 64) in;

layout(set = 0, binding = 0) readonly buffer Positions { vec4 items[]; } positions;
layout(set = 0, binding = 1) readonly buffer Triangles { uvec4 items[]; } triangles;
layout(set = 0, binding = 2) readonly buffer Edges { uvec4 items[]; } edges;
layout(set = 0, binding = 3) readonly buffer LightPositions { vec4 items[]; } light_positions;
layout(set = 0, binding = 4) writeonly buffer Volumes { vec4 items[]; } volumes;
// Two VkDrawIndirectCommand: words 0-3 the sides', 4-7 the caps'; the vertex counts are reset to
// 0 before the pass.
layout(set = 0, binding = 5) buffer Commands { uint words[]; } commands;
// Each triangle's facing() for the light: written by the triangles' dispatch, read by the edges'.
layout(set = 0, binding = 6) buffer Facings { float items[]; } facings;

layout(push_constant) uniform Entity {
    mat4 model;
    uint vertex_offset;    // into positions
    uint triangle_offset;  // into triangles
    uint triangle_count;
    uint edge_offset;      // into edges
    uint edge_count;
    uint caps_base;        // first output vertex of the caps, after room for every side
    uint closed;
    uint edges_phase;      // 0: the triangles' dispatch; 1: the edges'
} entity;

// An open mesh's edge record with one triangle has this as its second.
const uint NO_TRIANGLE = 0xffffffffu;

// The w of near-cap points (NEAR_CAP_W): volume.vert moves them back a little in depth.
const float CAP = 2.0;

vec3 world_position(uint v) {
    return (entity.model * vec4(positions.items[entity.vertex_offset + v].xyz, 1.0)).xyz;
}

// The direction from p toward the light (not normalised).
vec3 toward(vec4 light, vec3 p) {
    return light.xyz - p * light.w;
}

// The point at infinity that p's shadow runs to.
vec4 beyond(vec4 light, vec3 p) {
    return vec4(p * light.w - light.xyz, 0.0);
}

void put(uint at, vec4 a, vec4 b, vec4 c) {
    volumes.items[at] = a;
    volumes.items[at + 1u] = b;
    volumes.items[at + 2u] = c;
}

// Reserves n output vertices of the sides' draw (0) or the caps' (1) and returns the first.
uint reserve(uint draw, uint n) {
    uint first = atomicAdd(commands.words[4u * draw], n);
    return draw == 0u ? first : entity.caps_base + first;
}

float facing(uvec4 tri, vec4 light) {
    vec3 a = world_position(tri.x);
    vec3 b = world_position(tri.y);
    vec3 c = world_position(tri.z);
    return dot(cross(b - a, c - a), toward(light, a));
}

// +1 when triangle t, turned to face away from the light, runs the edge a -> b; -1 when it runs
// b -> a; 0 when it has no volume (edge on to the light, or no triangle).
int dark_direction(uint t, uint a, uint b) {
    if (t == NO_TRIANGLE) {
        return 0;
    }
    uvec4 tri = triangles.items[entity.triangle_offset + t];
    float f = facings.items[entity.triangle_offset + t];
    if (f == 0.0) {
        return 0;
    }
    bool runs = (tri.x == a && tri.y == b) || (tri.y == a && tri.z == b) || (tri.z == a && tri.x == b);
    return runs != (f > 0.0) ? 1 : -1;
}

// The side quad over edge u -> v, extruded away from the light. A directional light's second
// triangle is degenerate (both far corners are its one point at infinity) and is left out.
void side(vec3 u, vec3 v, vec4 light) {
    uint at = reserve(0u, light.w != 0.0 ? 6u : 3u);
    put(at, vec4(u, 1.0), vec4(v, 1.0), beyond(light, v));
    if (light.w != 0.0) {
        put(at + 3u, vec4(u, 1.0), beyond(light, v), beyond(light, u));
    }
}

void main() {
    uint item = gl_GlobalInvocationID.x;
    vec4 light = light_positions.items[0];
    if (entity.edges_phase == 0u) {
        if (item >= entity.triangle_count) {
            return;
        }
        uvec4 tri = triangles.items[entity.triangle_offset + item];
        vec3 p[3] = vec3[3](world_position(tri.x), world_position(tri.y), world_position(tri.z));
        // Kept, so that the edges see this very facing for the triangle.
        float f = facing(tri, light);
        facings.items[entity.triangle_offset + item] = f;
        // A closed mesh's lit triangles cast nothing; an open mesh's are turned to face away,
        // and only those edge on to the light cast nothing.
        bool casts = entity.closed != 0u ? !(f > 0.0) : f != 0.0;
        if (!casts) {
            return;
        }
        if (f > 0.0) {
            vec3 s = p[1];
            p[1] = p[2];
            p[2] = s;
        }
        // A directional light's far cap is its one point at infinity: nothing to draw.
        uint at = reserve(1u, light.w != 0.0 ? 6u : 3u);
        put(at, vec4(p[0], CAP), vec4(p[2], CAP), vec4(p[1], CAP));
        if (light.w != 0.0) {
            put(at + 3u, beyond(light, p[0]), beyond(light, p[1]), beyond(light, p[2]));
        }
        return;
    }
    uint e = item;
    if (e >= entity.edge_count) {
        return;
    }
    uvec4 edge = edges.items[entity.edge_offset + e];
    if (entity.closed != 0u) {
        bool la = facings.items[entity.triangle_offset + edge.z] > 0.0;
        bool lb = facings.items[entity.triangle_offset + edge.w] > 0.0;
        if (la == lb) {
            return;
        }
        vec3 a = world_position(edge.x);
        vec3 b = world_position(edge.y);
        // Along the edge in the dark triangle's direction.
        if (la) {
            side(b, a, light);
        } else {
            side(a, b, light);
        }
        return;
    }
    int da = dark_direction(edge.z, edge.x, edge.y);
    int db = dark_direction(edge.w, edge.x, edge.y);
    // Two turned triangles running the edge opposite ways share a side that cancels.
    if (da == -db) {
        return;
    }
    vec3 a = world_position(edge.x);
    vec3 b = world_position(edge.y);
    int d[2] = int[2](da, db);
    for (uint k = 0u; k < 2u; ++k) {
        if (d[k] > 0) {
            side(a, b, light);
        } else if (d[k] < 0) {
            side(b, a, light);
        }
    }
}
