// The BSP shadow system's segments (seed 003): world-space vertices with their material, and
// with BSP_DIRECT the relit colour of the vertex from the GEMV, interpolated (Gouraud).
#include "common/frame.glsl"

#ifdef BSP_DIRECT
layout(set = 0, binding = 1) readonly buffer Colours { vec4 c[]; } colours;
#endif

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec3 in_albedo;
layout(location = 3) in vec3 in_emission;

layout(location = 0) out vec3 out_world;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec3 out_albedo;
layout(location = 3) out vec3 out_emission;
layout(location = 4) out vec3 out_direct;

void main() {
    out_world = in_position;
    out_normal = in_normal;
    out_albedo = in_albedo;
    out_emission = in_emission;
#ifdef BSP_DIRECT
    out_direct = colours.c[gl_VertexIndex].rgb;
#else
    out_direct = vec3(0.0);
#endif
    gl_Position = frame.view_proj * vec4(in_position, 1.0);
}
