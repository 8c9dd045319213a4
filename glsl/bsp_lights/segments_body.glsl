// The BSP shadow system's segments (Ridderhof 2002): world-space vertices with their material, and
// with BSP_DIRECT the relit colours of the vertex from the GEMV, interpolated (Gouraud): its
// front's, and its back's from the row `in_back` names (none: no light is behind it).
#include "common/frame.glsl"

#ifdef BSP_DIRECT
layout(set = 0, binding = 1) readonly buffer Colours { vec4 c[]; } colours;
#endif

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec3 in_albedo;
layout(location = 3) in vec3 in_emission;
layout(location = 4) in uint in_back;

layout(location = 0) out vec3 out_world;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec3 out_albedo;
layout(location = 3) out vec3 out_emission;
layout(location = 4) out vec3 out_direct;
layout(location = 5) out vec3 out_direct_back;

const uint NO_BACK = 0xffffffffu;

void main() {
    out_world = in_position;
    out_normal = in_normal;
    out_albedo = in_albedo;
    out_emission = in_emission;
#ifdef BSP_DIRECT
    out_direct = colours.c[gl_VertexIndex].rgb;
    out_direct_back = in_back == NO_BACK ? vec3(0.0) : colours.c[in_back].rgb;
#else
    out_direct = vec3(0.0);
    out_direct_back = vec3(0.0);
#endif
    gl_Position = frame.view_proj * vec4(in_position, 1.0);
}
