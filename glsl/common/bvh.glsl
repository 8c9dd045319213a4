// Closest or any hit of a ray against a BVH over triangles, built by src/raytrace/bvh.rs
// (whose CPU traversal mirrors this one). The including shader defines BVH_NODES_BINDING and
// BVH_TRIANGLES_BINDING (set 0 bindings of the tables `bvh_nodes` and `bvh_triangles`: corner
// and two edges in BVH leaf order) and BVH_TRIANGLE_COUNT before including this file.
// The tables are images (common/texel_table.glsl): a node is texels 2i (lo, index) and 2i + 1
// (hi, count), a triangle texels 3i to 3i + 2. A shader that defines BVH_ORDERED_SKIPS_BINDING
// (the table `bvh_skips` of Bvh::octant_skip_links) also gets trace_triangles_ordered.
#ifndef PENUMBRA_COMMON_BVH_GLSL
#define PENUMBRA_COMMON_BVH_GLSL

#include "common/texel_table.glsl"

const float NO_HIT = 3.0e38;
// Matches bvh::MAX_DEPTH: the build bounds the tree's depth by it.
const uint MAX_DEPTH = 64u;

struct Triangle {
    vec4 p0;
    vec4 e1;
    vec4 e2;
};

layout(set = 0, binding = BVH_NODES_BINDING, rgba32ui) readonly uniform uimage2D bvh_nodes;
layout(set = 0, binding = BVH_TRIANGLES_BINDING, rgba32ui) readonly uniform uimage2D bvh_triangles;

Triangle bvh_triangle(uint i) {
    Triangle t;
    t.p0 = table_vec4(bvh_triangles, 3u * i);
    t.e1 = table_vec4(bvh_triangles, 3u * i + 1u);
    t.e2 = table_vec4(bvh_triangles, 3u * i + 2u);
    return t;
}

// Moller-Trumbore, the same arithmetic as bvh::intersect_triangle.
bool hit_triangle(vec3 o, vec3 d, vec3 p0, vec3 e1, vec3 e2, float t_max, out float t, out vec2 uv) {
    t = NO_HIT;
    uv = vec2(0.0);
    vec3 pv = cross(d, e2);
    float det = dot(e1, pv);
    if (det == 0.0) {
        return false;
    }
    float inv = 1.0 / det;
    vec3 tv = o - p0;
    uv.x = dot(tv, pv) * inv;
    if (uv.x < 0.0 || uv.x > 1.0) {
        return false;
    }
    vec3 qv = cross(tv, e1);
    uv.y = dot(d, qv) * inv;
    if (uv.y < 0.0 || uv.x + uv.y > 1.0) {
        return false;
    }
    t = dot(e2, qv) * inv;
    return t > 0.0 && t < t_max;
}

// min and max written as selects, for the slab test below. GLSL's min and max must return the
// other operand where one is NaN, which llvmpipe compiles as the x86 min or max plus a compare
// and a blend (unless it can prove an operand is a number); `a < b ? a : b` is exactly x86's
// minps, one instruction. A finite ray brings no NaN to the slab test (zero direction components
// are replaced by 1e-30, so inv_d is finite), and there the results are bit for bit those of min
// and max (images compared byte for byte): 1.02-1.17x on the reference's rates on lavapipe
// (README, "Box tests as selects"). `precise` keeps the compiler from folding the selects back
// into NaN-aware min and max.
float select_min(float a, float b) {
    precise float m = a < b ? a : b;
    return m;
}

float select_max(float a, float b) {
    precise float m = a > b ? a : b;
    return m;
}

// Entry distance into node `i`'s box within [0, t_max], NO_HIT if the ray misses it; also the
// node's index (interior: second child, the first being the next node; leaf: first triangle) and
// count (triangles in a leaf, 0 for interior nodes) from the same two texels, so that descending
// into the node needs no second fetch.
float node_entry(uint i, vec3 o, vec3 inv_d, float t_max, out uint index, out uint count) {
    uvec4 a = table_texel(bvh_nodes, 2u * i);
    uvec4 b = table_texel(bvh_nodes, 2u * i + 1u);
    index = a.w;
    count = b.w;
    vec3 t0 = (uintBitsToFloat(a.xyz) - o) * inv_d;
    vec3 t1 = (uintBitsToFloat(b.xyz) - o) * inv_d;
    bvec3 t0_nearer = lessThan(t0, t1);
    precise vec3 near = mix(t1, t0, t0_nearer);
    precise vec3 far = mix(t0, t1, t0_nearer);
    float enter = select_max(select_max(near.x, near.y), select_max(near.z, 0.0));
    float exit = select_min(select_min(far.x, far.y), select_min(far.z, t_max));
    return enter <= exit ? enter : NO_HIT;
}

// The leaf's triangles index .. index + count - 1 against the ray: each hit closer than t_max
// lowers it and becomes the hit (slot and barycentrics). True only for `any_hit` and a hit, which
// ends the query; the walks share it.
bool hit_leaf(uint index, uint count, vec3 o, vec3 d, bool any_hit, inout float t_max, inout int triangle, inout vec2 uv) {
    for (uint k = 0u; k < count; ++k) {
        uint slot = index + k;
        Triangle tri = bvh_triangle(slot);
        float t;
        vec2 b;
        if (hit_triangle(o, d, tri.p0.xyz, tri.e1.xyz, tri.e2.xyz, t_max, t, b)) {
            t_max = t;
            triangle = int(slot);
            uv = b;
            if (any_hit) {
                return true;
            }
        }
    }
    return false;
}

// trace_triangles' stack of nodes still to visit, with their entry distances, indices and counts
// (kept from the box test, so a node taken off the stack is not fetched again: 1.05-1.12x on
// llvmpipe). Private to each invocation; module scope so that `pop_closer` reaches it without
// copying it.
uint bvh_stack_node[MAX_DEPTH];
float bvh_stack_t[MAX_DEPTH];
uint bvh_stack_index[MAX_DEPTH];
uint bvh_stack_count[MAX_DEPTH];

// The most recently pushed node whose entry is closer than t_max, with its index and count,
// dropping those farther away; false when none is left.
bool pop_closer(inout uint sp, float t_max, out uint node, out uint index, out uint count) {
    node = 0u;
    index = 0u;
    count = 0u;
    while (sp > 0u) {
        --sp;
        if (bvh_stack_t[sp] < t_max) {
            node = bvh_stack_node[sp];
            index = bvh_stack_index[sp];
            count = bvh_stack_count[sp];
            return true;
        }
    }
    return false;
}

// Closest triangle hit closer than t_max (which it lowers), or with `any_hit` the first found.
// While-while (Aila and Laine 2009): every lane descends through interior nodes until it reaches
// a leaf, then the lanes test their leaves together, so SIMD lanes at different kinds of node do
// not take turns. The tree is rooted at node `root`: several trees may share the tables one
// after the other, their indices counted from the start of the tables (glsl/prt/rays.comp).
// The stack holds MAX_DEPTH entries, the depth bvh::Bvh::build bounds every tree by.
bool trace_triangles_from(uint root, vec3 o, vec3 d, bool any_hit, inout float t_max, out int triangle, out vec2 uv) {
    triangle = -1;
    uv = vec2(0.0);
    if (BVH_TRIANGLE_COUNT == 0u) {
        return false;
    }
    // Zero components would give 0 * inf = NaN in the slab test.
    vec3 inv_d = 1.0 / mix(d, vec3(1e-30), equal(d, vec3(0.0)));
    uint sp = 0u;
    uint node = root;
    uint index;
    uint count;
    if (node_entry(root, o, inv_d, t_max, index, count) == NO_HIT) {
        return false;
    }
    bool done = false;
    while (!done) {
        while (count == 0u) {
            // Nearer child first; the other waits on the stack with its entry distance.
            uint a = node + 1u;
            uint c = index;
            uint a_index;
            uint a_count;
            uint c_index;
            uint c_count;
            float ta = node_entry(a, o, inv_d, t_max, a_index, a_count);
            float tc = node_entry(c, o, inv_d, t_max, c_index, c_count);
            if (tc < ta) {
                a = index;
                c = node + 1u;
                float swap_t = ta;
                ta = tc;
                tc = swap_t;
                uint swap_index = a_index;
                a_index = c_index;
                c_index = swap_index;
                uint swap_count = a_count;
                a_count = c_count;
                c_count = swap_count;
            }
            if (ta != NO_HIT) {
                if (tc != NO_HIT && sp < MAX_DEPTH) {
                    bvh_stack_node[sp] = c;
                    bvh_stack_t[sp] = tc;
                    bvh_stack_index[sp] = c_index;
                    bvh_stack_count[sp] = c_count;
                    ++sp;
                }
                node = a;
                index = a_index;
                count = a_count;
            } else if (!pop_closer(sp, t_max, node, index, count)) {
                done = true;
                break;
            }
        }
        if (done) {
            break;
        }
        if (hit_leaf(index, count, o, d, any_hit, t_max, triangle, uv)) {
            return true;
        }
        done = !pop_closer(sp, t_max, node, index, count);
    }
    return triangle >= 0;
}

bool trace_triangles(vec3 o, vec3 d, bool any_hit, inout float t_max, out int triangle, out vec2 uv) {
    return trace_triangles_from(0u, o, d, any_hit, t_max, triangle, uv);
}

#ifdef BVH_ORDERED_SKIPS_BINDING
// Per node and ray octant, the node after its subtree in the order that octant takes children,
// bit 31 set where it takes the second child first (Bvh::octant_skip_links): eight words a node.
layout(set = 0, binding = BVH_ORDERED_SKIPS_BINDING, rgba32ui) readonly uniform uimage2D bvh_skips;

// trace_triangles without a stack: the nodes in an order fixed per ray octant, each child
// before the other where the ray runs from it toward the other, past a subtree whose box the
// ray misses or enters beyond t_max. It tests the same boxes as the nearer-first stack walk
// (within 2 %, measured on the CPU twin for rays leaving a furnace sphere's and a box's walls),
// one a step with a third texel for the link, and keeps no stack: on llvmpipe a private array
// indexed per lane is a scalar store or load per lane, and trace_triangles pushes and pops four.
// With it the reference traces 1.02-1.14x as fast on lavapipe and 0.79-0.92x as fast on the
// H200, which keeps a stack in fast memory, so the reference picks the walk per device
// (src/reference/features.rs, BvhWalk; README, "The reference against Mitsuba 3").
bool trace_triangles_ordered(vec3 o, vec3 d, bool any_hit, inout float t_max, out int triangle, out vec2 uv) {
    triangle = -1;
    uv = vec2(0.0);
    if (BVH_TRIANGLE_COUNT == 0u) {
        return false;
    }
    vec3 inv_d = 1.0 / mix(d, vec3(1e-30), equal(d, vec3(0.0)));
    uint octant = (d.x < 0.0 ? 1u : 0u) | (d.y < 0.0 ? 2u : 0u) | (d.z < 0.0 ? 4u : 0u);
    // The root's link in every octant is the node count.
    uint end = table_packed(bvh_skips, octant) & 0x7fffffffu;
    uint node = 0u;
    // While-while, as trace_triangles: each lane goes on through interior nodes and missed
    // boxes until it reaches a leaf it enters, then the lanes test their leaves together.
    while (node < end) {
        uint index = 0u;
        uint count = 0u;
        uint word = 0u;
        while (node < end) {
            float entry = node_entry(node, o, inv_d, t_max, index, count);
            word = table_packed(bvh_skips, 8u * node + octant);
            if (entry != NO_HIT && count != 0u) {
                break;
            }
            node = entry == NO_HIT ? (word & 0x7fffffffu) : ((word >> 31u) != 0u ? index : node + 1u);
        }
        if (node >= end) {
            break;
        }
        if (hit_leaf(index, count, o, d, any_hit, t_max, triangle, uv)) {
            return true;
        }
        node = word & 0x7fffffffu;
    }
    return triangle >= 0;
}
#endif

#ifdef BVH_SKIPS_BINDING
// Per node, the node after its subtree (Bvh::skip_links).
// Four links a texel.
layout(set = 0, binding = BVH_SKIPS_BINDING, rgba32ui) readonly uniform uimage2D bvh_skips;

uint bvh_skip(uint i) {
    return table_packed(bvh_skips, i);
}

// Whether a triangle of the tree rooted at node `root` lies on the ray closer than t_max: shadow
// rays, where the order of the hits does not matter, walk the nodes in storage order without a
// stack, past a subtree whose box the ray misses. Several trees may share the buffers, one
// after the other, with their node and triangle indices and skip links counted from the start
// of the buffers (glsl/prt/rays.comp); the walk ends at the root's skip link. `complete` is
// false when the walk was cut short (a device that bounds an invocation's loop iterations), and
// the answer then means nothing.
bool occluded_in(uint root, vec3 o, vec3 d, float t_max, out bool complete) {
    vec3 inv_d = 1.0 / mix(d, vec3(1e-30), equal(d, vec3(0.0)));
    uint end = bvh_skip(root);
    uint node = root;
    while (node < end) {
        uint index;
        uint count;
        if (node_entry(node, o, inv_d, t_max, index, count) == NO_HIT) {
            node = bvh_skip(node);
            continue;
        }
        if (count == 0u) {
            node += 1u;
            continue;
        }
        int triangle = -1;
        vec2 uv;
        if (hit_leaf(index, count, o, d, true, t_max, triangle, uv)) {
            complete = true;
            return true;
        }
        node = bvh_skip(node);
    }
    complete = node >= end;
    return false;
}

// occluded_in for the one tree of the buffers (rooted at node 0).
bool occluded(vec3 o, vec3 d, float t_max, out bool complete) {
    complete = true;
    if (BVH_TRIANGLE_COUNT == 0u) {
        return false;
    }
    return occluded_in(0u, o, d, t_max, complete);
}
#endif

#endif
