#version 460
// Clip-space positions straight from the vertex buffer: test geometry and debug overlays.
layout(location = 0) in vec4 in_clip;

void main() {
    gl_Position = in_clip;
}
