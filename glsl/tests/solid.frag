#version 460
// One flat colour from push constants.
layout(push_constant) uniform Solid {
    vec4 color;
} solid;

layout(location = 0) out vec4 out_color;

void main() {
    out_color = solid.color;
}
