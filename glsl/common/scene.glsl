// The scene as every raster method draws it: the material record, the per-draw push constants
// and (in vertex shaders that define PENUMBRA_SCENE_VERTEX first) the interleaved vertex.
// Matches `GpuMaterial`, `DrawPush` and `Vertex`/`vertex_layout` in src/gpu_scene/mod.rs.
#ifndef PENUMBRA_SCENE_GLSL
#define PENUMBRA_SCENE_GLSL

struct Material {
    vec4 albedo;    // rgb: diffuse albedo; w: opacity (1 opaque, < 1 translucent)
    vec4 specular;  // rgb: Blinn-Phong specular colour; w: exponent
    vec4 emission;  // rgb: emitted radiance
    uvec4 maps;     // x: has a normal map; y: one-sided emitter (no emission from the back)
};

layout(push_constant) uniform Draw {
    mat4 model;
    uint material;
} draw;

#ifdef PENUMBRA_SCENE_VERTEX
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_tangent;
#endif

#endif
