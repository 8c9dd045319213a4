#version 460
// Entity shadow volumes for each light in light_positions (the frame passes one at a time, into
// one slot), from edge adjacency: one invocation per
// triangle (its near and far cap if it faces away from the light) and, for closed meshes, per
// edge (a side quad if it is a silhouette edge: one adjacent triangle lit, the other dark).
// Open meshes get a closed volume per triangle instead. A light is homogeneous: (position, 1),
// or for a directional light (toward it, 0), whose volumes all run to one point at infinity, so
// their far caps are degenerate and draw nothing. Every invocation owns fixed output
// slots; slots with nothing to draw get degenerate triangles, which rasterize to nothing.
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
    uint edge_count;       // 0 for open meshes
    uint out_offset;       // first output vertex (vec4) of light 0
    uint light_stride;     // output vertices per light
    uint closed;
} entity;

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

bool lit(uint t, vec4 light) {
    uvec4 tri = triangles.items[entity.triangle_offset + t];
    vec3 a = world_position(tri.x);
    vec3 b = world_position(tri.y);
    vec3 c = world_position(tri.z);
    return dot(cross(b - a, c - a), toward(light, a)) > 0.0;
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

void main() {
    uint item = gl_GlobalInvocationID.x;
    uint li = gl_GlobalInvocationID.y;
    vec4 light = light_positions.items[li];
    uint base = entity.out_offset + li * entity.light_stride;
    if (entity.closed == 0u) {
        if (item >= entity.triangle_count) {
            return;
        }
        uint at = base + 24u * item;
        uvec4 tri = triangles.items[entity.triangle_offset + item];
        vec3 p[3] = vec3[3](world_position(tri.x), world_position(tri.y), world_position(tri.z));
        float facing = dot(cross(p[1] - p[0], p[2] - p[0]), toward(light, p[0]));
        if (facing == 0.0) {
            nothing(at, 8u);
            return;
        }
        if (facing > 0.0) {
            vec3 s = p[1];
            p[1] = p[2];
            p[2] = s;
        }
        vec4 near[3];
        vec4 far[3];
        for (uint i = 0u; i < 3u; ++i) {
            near[i] = vec4(p[i], 1.0);
            far[i] = beyond(light, p[i]);
        }
        put(at, vec4(p[0], CAP), vec4(p[2], CAP), vec4(p[1], CAP));
        put(at + 3u, far[0], far[1], far[2]);
        for (uint i = 0u; i < 3u; ++i) {
            uint j = (i + 1u) % 3u;
            put(at + 6u + 6u * i, near[i], near[j], far[j]);
            put(at + 9u + 6u * i, near[i], far[j], far[i]);
        }
        return;
    }
    if (item < entity.triangle_count) {
        uint at = base + 6u * item;
        if (lit(item, light)) {
            nothing(at, 2u);
            return;
        }
        uvec4 tri = triangles.items[entity.triangle_offset + item];
        vec3 a = world_position(tri.x);
        vec3 b = world_position(tri.y);
        vec3 c = world_position(tri.z);
        put(at, vec4(a, CAP), vec4(c, CAP), vec4(b, CAP));
        put(at + 3u, beyond(light, a), beyond(light, b), beyond(light, c));
        return;
    }
    uint e = item - entity.triangle_count;
    if (e >= entity.edge_count) {
        return;
    }
    uint at = base + 6u * entity.triangle_count + 6u * e;
    uvec4 edge = edges.items[entity.edge_offset + e];
    bool la = lit(edge.z, light);
    bool lb = lit(edge.w, light);
    if (la == lb) {
        nothing(at, 2u);
        return;
    }
    // Along the edge in the dark triangle's direction.
    vec3 u = world_position(la ? edge.y : edge.x);
    vec3 v = world_position(la ? edge.x : edge.y);
    put(at, vec4(u, 1.0), vec4(v, 1.0), beyond(light, v));
    put(at + 3u, vec4(u, 1.0), beyond(light, v), beyond(light, u));
}
