#version 460
// The displaced height-field mesh, generated from the vertex index: two triangles per cell of
// the res x res sample grid, vertex (i, j) at the sample's world position with this frame's
// height; uv addresses the shading image at the same sample. It is also the scene mesh's uv,
// ((i + 1/2)/res, (j + 1/2)/res): a function of the world position alone, so the material's
// albedo map lands where the reference puts it whatever resolution the method works at.
#include "common/frame.glsl"

layout(set = 0, binding = 1) uniform sampler2D heights;

layout(push_constant) uniform Terrain {
    vec4 origin;   // x: world x of sample 0, y: world z of sample 0, z: spacing, w: res
    vec4 albedo;   // rgb; w: world y of height 0 (the field's translation)
    vec4 emission; // rgb
} terrain;

layout(location = 0) out vec2 out_uv;

void main() {
    int res = int(terrain.origin.w);
    int cell = gl_VertexIndex / 6;
    int corner = gl_VertexIndex % 6;
    // a, d, c, a, c, b of the cell (i, j): counter-clockwise seen from +y, as the CPU mesh.
    const ivec2 offsets[6] = ivec2[6](ivec2(0, 0), ivec2(0, 1), ivec2(1, 1), ivec2(0, 0), ivec2(1, 1), ivec2(1, 0));
    ivec2 ij = ivec2(cell % (res - 1), cell / (res - 1)) + offsets[corner];
    float h = texelFetch(heights, ij, 0).r;
    vec3 world = vec3(terrain.origin.x + float(ij.x) * terrain.origin.z, terrain.albedo.w + h, terrain.origin.y + float(ij.y) * terrain.origin.z);
    out_uv = (vec2(ij) + 0.5) / float(res);
    gl_Position = frame.view_proj * vec4(world, 1.0);
}
