#version 460
// Dickson et al. 2011's vertex wind (digest 6.1), applied to one object's vertices in the scene's vertex
// buffer before any method draws the frame: src/scene/motion.rs is its CPU twin (the reference
// path tracer's geometry), with the formula.
// c = cos(rate*t + (x + z)/20 - y*y/70 + z*z/300), (x, y, z) = rest position / unit;
// position.y += amplitude*unit*w*c; tangent and bitangent += (0, 0.1*w*c, 0); normal = their cross.

layout(local_size_x = 64) in;

// 12 floats a vertex: position (3), normal (3), uv (2), tangent (4), as src/gpu_scene's Vertex.
layout(set = 0, binding = 0) readonly buffer Rest { float v[]; } rest;
layout(set = 0, binding = 1) readonly buffer Weights { float w[]; } weights;
layout(set = 0, binding = 2) buffer Vertices { float v[]; } vertices;

layout(push_constant) uniform Wind {
    float time;
    float amplitude;
    float rate;
    float unit;
    uint first;  // the object's first vertex in the scene's vertex buffer
    uint count;
} wind;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= wind.count) {
        return;
    }
    uint s = i * 12u;
    vec3 p = vec3(rest.v[s], rest.v[s + 1u], rest.v[s + 2u]);
    vec3 n = vec3(rest.v[s + 3u], rest.v[s + 4u], rest.v[s + 5u]);
    vec4 t = vec4(rest.v[s + 8u], rest.v[s + 9u], rest.v[s + 10u], rest.v[s + 11u]);
    float w = weights.w[i];
    vec3 q = p / wind.unit;
    float c = cos(wind.rate * wind.time + (q.x + q.z) / 20.0 - q.y * q.y / 70.0 + q.z * q.z / 300.0);
    p.y += wind.amplitude * wind.unit * w * c;
    float handed = t.w < 0.0 ? -1.0 : 1.0;
    vec3 b = cross(n, t.xyz) * handed;
    vec3 d = vec3(0.0, 0.1 * w * c, 0.0);
    vec3 t2 = t.xyz + d;
    vec3 b2 = b + d;
    vec3 n2 = cross(t2, b2) * handed;
    n2 = dot(n2, n2) > 0.0 ? normalize(n2) : n;
    t2 = dot(t2, t2) > 0.0 ? normalize(t2) : t.xyz;
    uint o = (wind.first + i) * 12u;
    vertices.v[o] = p.x;
    vertices.v[o + 1u] = p.y;
    vertices.v[o + 2u] = p.z;
    vertices.v[o + 3u] = n2.x;
    vertices.v[o + 4u] = n2.y;
    vertices.v[o + 5u] = n2.z;
    vertices.v[o + 6u] = rest.v[s + 6u];
    vertices.v[o + 7u] = rest.v[s + 7u];
    vertices.v[o + 8u] = t2.x;
    vertices.v[o + 9u] = t2.y;
    vertices.v[o + 10u] = t2.z;
    vertices.v[o + 11u] = t.w;
}
