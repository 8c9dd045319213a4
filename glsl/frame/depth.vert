#version 460
// The renderer's depth pass when a configuration has no base term: the scene's depth alone, so
// that direct and indirect terms drawn on their own test against it. The same transform as
// every method's scene vertex shader, so depths match theirs exactly.
#include "common/frame.glsl"
#define PENUMBRA_SCENE_VERTEX
#include "common/scene.glsl"

void main() {
    gl_Position = frame.view_proj * (draw.model * vec4(in_position, 1.0));
}
