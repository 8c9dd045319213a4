#version 460
// Entity shadow volumes for each light in light_positions (the frame passes one at a time, into
// one slot), from edge adjacency: one invocation per triangle (its near and far cap) and one per
// edge (its sides). A closed mesh casts from its dark triangles (facing away from the light),
// and an edge gets a side quad if it is a silhouette edge: one adjacent triangle lit, the other
// dark. An open mesh casts from both sides: every triangle is turned to face away from the
// light and capped, and an edge gets each triangle's side unless the two turned triangles run
// it opposite ways, where the sides would cancel (so a flat sheet's volume has sides only on its
// border, and no coincident pairs inside). A light is homogeneous: (position, 1), or for a
// directional light (toward it, 0), whose volumes all run to one point at infinity, so their
// far caps are degenerate and draw nothing. Every invocation owns fixed output slots; slots with
// nothing to draw get degenerate triangles, which rasterize to nothing. The edges' slots come
// first, then the triangles': with wrapping stencil operations the order changes no count.
// CPU mirror: silhouette_volume in src/lighting/shadow_volumes/volumes.rs.
layout(local_size_x = 64) in;

layout(set = 0, binding = 0) readonly buffer Positions { vec4 items[]; } positions;
layout(set = 0, binding = 1) readonly buffer Triangles { uvec4 items[]; } triangles;
layout(set = 0, binding = 2) readonly buffer Edges { uvec4 items[]; } edges;
layout(set = 0, binding = 3) readonly buffer LightPositions { vec4 items[]; } light_positions;
layout(set = 0, binding = 4) writeonly buffer Volumes { vec4 items[]; } volumes;

layout(push_constant) uniform Entity {
    mat4 model;
    uint vertex_offset;    // into positions
    uint triangle_offset;  // into triangles
    uint triangle_count;
    uint edge_offset;      // into edges
    uint edge_count;
    uint out_offset;       // first output vertex (vec4) of light 0
    uint light_stride;     // output vertices per light
    uint closed;
    uint shared_edges;     // open meshes: the first edge records, those of two triangles
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

void nothing(uint at, uint triangles_out) {
    for (uint i = 0u; i < 3u * triangles_out; ++i) {
        volumes.items[at + i] = vec4(0.0, 0.0, 0.0, 1.0);
    }
}

// The output vertices of the first e edge slots: a side quad per edge, but two for an open
// mesh's edge of two triangles (the first shared_edges records).
uint edge_vertices(uint e) {
    if (entity.closed != 0u) {
        return 6u * e;
    }
    uint two = min(e, entity.shared_edges);
    return 12u * two + 6u * (e - two);
}

float facing(uvec4 tri, vec4 light) {
    vec3 a = world_position(tri.x);
    vec3 b = world_position(tri.y);
    vec3 c = world_position(tri.z);
    return dot(cross(b - a, c - a), toward(light, a));
}

// +1 when triangle t, turned to face away from the light, runs the edge a -> b; -1 when it runs
// b -> a; 0 when it has no volume (edge on to the light, or no triangle).
int dark_direction(uint t, uint a, uint b, vec4 light) {
    if (t == NO_TRIANGLE) {
        return 0;
    }
    uvec4 tri = triangles.items[entity.triangle_offset + t];
    float f = facing(tri, light);
    if (f == 0.0) {
        return 0;
    }
    bool runs = (tri.x == a && tri.y == b) || (tri.y == a && tri.z == b) || (tri.z == a && tri.x == b);
    return runs != (f > 0.0) ? 1 : -1;
}

// The side quad over edge u -> v, extruded away from the light.
void side(uint at, vec3 u, vec3 v, vec4 light) {
    put(at, vec4(u, 1.0), vec4(v, 1.0), beyond(light, v));
    put(at + 3u, vec4(u, 1.0), beyond(light, v), beyond(light, u));
}

void main() {
    uint item = gl_GlobalInvocationID.x;
    uint li = gl_GlobalInvocationID.y;
    vec4 light = light_positions.items[li];
    uint base = entity.out_offset + li * entity.light_stride;
    if (item < entity.triangle_count) {
        uint at = base + edge_vertices(entity.edge_count) + 6u * item;
        uvec4 tri = triangles.items[entity.triangle_offset + item];
        vec3 p[3] = vec3[3](world_position(tri.x), world_position(tri.y), world_position(tri.z));
        // The same function as the edges' test, so both see one facing for this triangle.
        float f = facing(tri, light);
        // A closed mesh's lit triangles cast nothing; an open mesh's are turned to face away,
        // and only those edge on to the light cast nothing.
        bool casts = entity.closed != 0u ? !(f > 0.0) : f != 0.0;
        if (!casts) {
            nothing(at, 2u);
            return;
        }
        if (f > 0.0) {
            vec3 s = p[1];
            p[1] = p[2];
            p[2] = s;
        }
        put(at, vec4(p[0], CAP), vec4(p[2], CAP), vec4(p[1], CAP));
        put(at + 3u, beyond(light, p[0]), beyond(light, p[1]), beyond(light, p[2]));
        return;
    }
    uint e = item - entity.triangle_count;
    if (e >= entity.edge_count) {
        return;
    }
    uvec4 edge = edges.items[entity.edge_offset + e];
    vec3 a = world_position(edge.x);
    vec3 b = world_position(edge.y);
    if (entity.closed != 0u) {
        uint at = base + edge_vertices(e);
        bool la = facing(triangles.items[entity.triangle_offset + edge.z], light) > 0.0;
        bool lb = facing(triangles.items[entity.triangle_offset + edge.w], light) > 0.0;
        if (la == lb) {
            nothing(at, 2u);
            return;
        }
        // Along the edge in the dark triangle's direction.
        if (la) {
            side(at, b, a, light);
        } else {
            side(at, a, b, light);
        }
        return;
    }
    uint at = base + edge_vertices(e);
    int da = dark_direction(edge.z, edge.x, edge.y, light);
    int db = dark_direction(edge.w, edge.x, edge.y, light);
    int d[2] = int[2](da, db);
    // An edge of one triangle has one side slot.
    uint slots = edge.w == NO_TRIANGLE ? 1u : 2u;
    for (uint k = 0u; k < slots; ++k) {
        // Two turned triangles running the edge opposite ways share a side that cancels.
        if (d[k] == 0 || da == -db) {
            nothing(at + 6u * k, 2u);
        } else if (d[k] > 0) {
            side(at + 6u * k, a, b, light);
        } else {
            side(at + 6u * k, b, a, light);
        }
    }
}
