// The raster baker's hemisphere-to-tile mappings, the twin of src/lighting/prt/mapping.rs.
// Directions are in the vertex camera's frame: x tangent, y bitangent, z normal. A tile spans
// [-1, 1]^2; pixel (i, j) has its centre at -1 + (2i + 1) / T.
#ifndef PENUMBRA_PRT_MAPPING_GLSL
#define PENUMBRA_PRT_MAPPING_GLSL

const int PRT_ORTHOGRAPHIC = 0;
const int PRT_STEREOGRAPHIC = 1;
const int PRT_EQUAL_AREA = 2;

// Where the unit direction d lands (Listing 2.4's x, y for the orthographic mapping).
vec2 prt_project(int mapping, vec3 d) {
    if (mapping == PRT_ORTHOGRAPHIC) {
        return d.xy;
    }
    if (mapping == PRT_STEREOGRAPHIC) {
        return d.xy / max(1.0 + d.z, 1e-12);
    }
    float r_xy = length(d.xy);
    return r_xy > 0.0 ? d.xy / r_xy * sqrt(max(1.0 - d.z, 0.0)) : vec2(0.0);
}

// The direction landing at st; outside the unit disk, the horizon in st's direction.
vec3 prt_unproject_clamped(int mapping, vec2 st) {
    float r2 = dot(st, st);
    if (r2 >= 1.0) {
        float r = sqrt(r2);
        return r > 0.0 ? vec3(st / r, 0.0) : vec3(0.0, 0.0, 1.0);
    }
    if (mapping == PRT_ORTHOGRAPHIC) {
        return vec3(st, sqrt(1.0 - r2));
    }
    if (mapping == PRT_STEREOGRAPHIC) {
        float k = 2.0 / (1.0 + r2);
        return vec3(st * k, (1.0 - r2) / (1.0 + r2));
    }
    return vec3(st * sqrt(2.0 - r2), 1.0 - r2);
}

// One receiver: the vertex camera (position, frame). w of `position` is 1 for a real vertex
// and 0 for the empty vertices that pad a batch.
struct PrtReceiver {
    vec4 position;
    vec4 tangent;
    vec4 bitangent;
    vec4 normal;
};

#endif
