#version 460
// A full-screen triangle on the far plane (depth 1): drawn with LESS_OR_EQUAL and no depth
// writes after the geometry, it covers exactly the pixels nothing was drawn on.
layout(location = 0) out vec2 out_ndc;

void main() {
    vec2 uv = vec2((gl_VertexIndex << 1) & 2, gl_VertexIndex & 2);
    out_ndc = uv * 2.0 - 1.0;
    gl_Position = vec4(out_ndc, 1.0, 1.0);
}
