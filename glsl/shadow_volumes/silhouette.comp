#version 460
// Entity shadow volumes for one light (the frame passes one light at a time, into one buffer),
// from edge adjacency, in two dispatches: one invocation per triangle (its facing, kept for the
// edges, and whether its volume reaches the near plane), then one per triangle or edge,
// whichever are more (a triangle's near and far cap, an edge's sides from its triangles'
// facings). A closed mesh casts from its dark triangles (facing away from the light), and an
// edge gets a side quad if it is a silhouette edge: one adjacent triangle lit, the other dark.
// An open mesh casts from both sides: every triangle is turned to face away from the light and
// capped, and an edge gets each triangle's side unless the two turned triangles run it opposite
// ways, where the sides would cancel (so a flat sheet's volume has sides only on its border, and
// no coincident pairs inside). A light is homogeneous: (position, 1), or for a directional light
// (toward it, 0), whose volumes all run to one point at infinity, so their far caps are
// degenerate and draw nothing.
// Z-pass where it is exact (Everitt & Kilgard 2002, "Practical and Robust Stenciled Shadow
// Volumes"): z-fail needs the caps, which cost most of the fill, and counts the same as z-pass
// wherever the near plane cuts no volume. A volume reaches the near plane's rectangle only if
// its triangle meets the near-clip volume, the hull of the light and that rectangle (every
// segment from a point of it to the light). The first dispatch tests each casting triangle
// against the hull's planes (a triangle wholly outside one misses it; a test that cannot tell
// keeps z-fail) and marks its entity; the second then writes caps for z-fail only, and the sides
// into the z-fail or the z-pass draw, entity by entity.
// Output is compacted: an invocation with something to draw reserves its vertices with an atomic
// add on the count of one of the indirect draws, sides (from vertex 0) or caps (from caps_base),
// so nothing is written or drawn for the many edges that are not silhouettes, or for a
// directional light's degenerate triangles. (Leaving out the triangles the view clips away
// whole cost the pass more than it saved the draws on a 269k-triangle scene.) The order within
// a draw then varies from frame to frame; with wrapping stencil operations it changes no count,
// and sides still come before caps for the saturating negative control.
// CPU mirror: silhouette_volume in src/lighting/shadow_volumes/volumes.rs; the hull's planes:
// near_clip in src/lighting/shadow_volumes/near_clip.rs.
layout(local_size_x = 64) in;

layout(set = 0, binding = 0) readonly buffer Positions { vec4 items[]; } positions;
layout(set = 0, binding = 1) readonly buffer Triangles { uvec4 items[]; } triangles;
layout(set = 0, binding = 2) readonly buffer Edges { uvec4 items[]; } edges;
// The light; then, when entity.near_test is set, the near-clip volume's five planes (outward
// normal, offset: outside where dot(n, p) + offset > 0) and its rectangle's four corners (w: the
// distance a triangle's plane must clear them by).
layout(set = 0, binding = 3) readonly buffer LightPositions { vec4 items[]; } light_positions;
layout(set = 0, binding = 4) writeonly buffer Volumes { vec4 items[]; } volumes;
// Three VkDrawIndirectCommand: words 0-3 the sides' for z-fail, 4-7 the caps', 8-11 the sides'
// for z-pass; the vertex counts are reset to 0 before the pass, and the third dispatch sets the
// z-pass sides' first vertex.
layout(set = 0, binding = 5) buffer Commands { uint words[]; } commands;
// Each triangle's facing() for the light: written by the triangles' dispatch, read by the edges'.
layout(set = 0, binding = 6) buffer Facings { float items[]; } facings;
// Per entity: nonzero when one of its volumes may reach the near plane, so that it counts by
// z-fail; the others count by z-pass (each entity's volumes are closed, so the two ways add up).
// Reset to 0 before the pass, or to 1 when no test is made.
layout(set = 0, binding = 7) buffer Near { uint items[]; } near_plane;

layout(push_constant) uniform Entity {
    mat4 model;
    uint vertex_offset;    // into positions
    uint triangle_offset;  // into triangles
    uint triangle_count;
    uint edge_offset;      // into edges
    uint edge_count;
    uint caps_base;        // first output vertex of the caps, after room for every side
    uint closed;
    uint edges_phase;      // 0: the triangles' dispatch; 1: the caps' and edges'; 2: finish
    uint near_test;        // 1: test against the near-clip volume; 0: no test (z-fail)
    uint index;            // the entity's word in near_plane
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

// Reserves n output vertices of draw 0 (the z-fail sides', up from vertex 0), 1 (the caps', up
// from caps_base) or 2 (the z-pass sides', down from caps_base, so that the two kinds of side
// share the room for every side; the third dispatch sets where draw 2 starts) and returns the
// first.
uint reserve(uint draw, uint n) {
    uint first = atomicAdd(commands.words[4u * draw], n);
    if (draw == 2u) {
        return entity.caps_base - first - n;
    }
    return draw == 1u ? entity.caps_base + first : first;
}

// Whether triangle p surely misses the near-clip volume: all its corners outside one of the
// hull's planes, or the hull (its rectangle's corners, and the light) wholly on one side of the
// triangle's own plane, which catches floors and walls larger than the hull.
bool misses_near_clip(vec3 p[3], vec4 light) {
    for (uint k = 0u; k < 5u; ++k) {
        vec4 h = light_positions.items[1u + k];
        if (dot(h.xyz, p[0]) + h.w > 0.0 && dot(h.xyz, p[1]) + h.w > 0.0 && dot(h.xyz, p[2]) + h.w > 0.0) {
            return true;
        }
    }
    vec3 n = cross(p[1] - p[0], p[2] - p[0]);
    float apex = light.w != 0.0 ? dot(n, light.xyz / light.w - p[0]) : dot(n, light.xyz);
    for (int sign = -1; sign <= 1; sign += 2) {
        bool clear = light.w != 0.0 ? float(sign) * apex > 0.0 : float(sign) * apex >= 0.0;
        for (uint k = 0u; k < 4u && clear; ++k) {
            vec4 c = light_positions.items[6u + k];
            clear = float(sign) * dot(n, c.xyz - p[0]) > c.w * length(n);
        }
        if (clear) {
            return true;
        }
    }
    return false;
}

float facing(vec3 p[3], vec4 light) {
    return dot(cross(p[1] - p[0], p[2] - p[0]), toward(light, p[0]));
}

// Whether a triangle of this facing casts a volume: a closed mesh's lit triangles cast nothing;
// an open mesh's are turned to face away, and only those edge on to the light cast nothing.
bool casts(float f) {
    return entity.closed != 0u ? !(f > 0.0) : f != 0.0;
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
void side(vec3 u, vec3 v, vec4 light, uint draw) {
    uint at = reserve(draw, light.w != 0.0 ? 6u : 3u);
    put(at, vec4(u, 1.0), vec4(v, 1.0), beyond(light, v));
    if (light.w != 0.0) {
        put(at + 3u, vec4(u, 1.0), beyond(light, v), beyond(light, u));
    }
}

// Triangle t's near and far cap, turned to face away from the light.
void caps(uint t, vec4 light) {
    uvec4 tri = triangles.items[entity.triangle_offset + t];
    float f = facings.items[entity.triangle_offset + t];
    if (!casts(f)) {
        return;
    }
    vec3 p[3] = vec3[3](world_position(tri.x), world_position(tri.y), world_position(tri.z));
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
}

// Edge e's sides, into draw 0 (z-fail) or 2 (z-pass).
void sides(uint e, vec4 light, uint draw) {
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
            side(b, a, light, draw);
        } else {
            side(a, b, light, draw);
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
            side(a, b, light, draw);
        } else if (d[k] < 0) {
            side(b, a, light, draw);
        }
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
        // Kept, so that the caps and edges see this very facing for the triangle.
        float f = facing(p, light);
        facings.items[entity.triangle_offset + item] = f;
        if (casts(f) && entity.near_test != 0u && !misses_near_clip(p, light)) {
            near_plane.items[entity.index] = 1u;
        }
        return;
    }
    if (entity.edges_phase == 2u) {
        // One invocation, after every entity's sides: where the z-pass sides' draw starts.
        if (item == 0u) {
            commands.words[10] = entity.caps_base - commands.words[8];
        }
        return;
    }
    bool near = near_plane.items[entity.index] != 0u;
    if (near && item < entity.triangle_count) {
        caps(item, light);
    }
    if (item < entity.edge_count) {
        sides(item, light, near ? 0u : 2u);
    }
}
