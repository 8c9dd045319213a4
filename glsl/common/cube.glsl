// Cube environments stored as one 2D map: the six n x n faces stacked top to bottom in Vulkan's
// layer order (+X, -X, +Y, -Y, +Z, -Z), so the sky pass and the path tracer read them with the
// same nearest-texel lookups as an equirect map. Face coordinates st in [-1, 1]^2: s runs with a
// face image's columns, t with its rows (top to bottom).
#ifndef PENUMBRA_COMMON_CUBE_GLSL
#define PENUMBRA_COMMON_CUBE_GLSL

// Matches Environment::cube_face in src/scene/types.rs (the Vulkan face selection table; ties
// go to x, then y).
uint cube_face(vec3 d, out vec2 st) {
    vec3 a = abs(d);
    uint face;
    float ma;
    vec2 sc;
    if (a.x >= a.y && a.x >= a.z) {
        ma = a.x;
        face = d.x >= 0.0 ? 0u : 1u;
        sc = vec2(d.x >= 0.0 ? -d.z : d.z, -d.y);
    } else if (a.y >= a.z) {
        ma = a.y;
        face = d.y >= 0.0 ? 2u : 3u;
        sc = vec2(d.x, d.y >= 0.0 ? d.z : -d.z);
    } else {
        ma = a.z;
        face = d.z >= 0.0 ? 4u : 5u;
        sc = vec2(d.z >= 0.0 ? d.x : -d.x, -d.y);
    }
    st = ma > 0.0 ? sc / ma : vec2(0.0);
    return face;
}

// Matches Environment::cube_dir: the un-normalised direction through st on `face`.
vec3 cube_dir(uint face, vec2 st) {
    switch (face) {
    case 0u: return vec3(1.0, -st.y, -st.x);
    case 1u: return vec3(-1.0, -st.y, st.x);
    case 2u: return vec3(st.x, 1.0, st.y);
    case 3u: return vec3(st.x, -1.0, -st.y);
    case 4u: return vec3(st.x, -st.y, 1.0);
    default: return vec3(-st.x, -st.y, -1.0);
    }
}

// The stacked map's texel (column, row) under st on `face` of n x n faces.
uvec2 cube_texel(uint face, vec2 st, uint n) {
    uvec2 c = min(uvec2(max((st + 1.0) * 0.5 * float(n), vec2(0.0))), uvec2(n - 1u));
    return uvec2(c.x, face * n + c.y);
}

#endif
