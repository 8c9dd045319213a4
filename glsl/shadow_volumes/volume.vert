#version 460
// Shadow-volume vertices: w = 1 points as they are; w = 0 points at infinity; w = 2 near-cap
// points, moved back by NEAR_CAP_DEPTH_OFFSET in depth so a lit surface lying on its own near
// cap tests as outside the volume (src/shadow_volumes/volumes.rs). World caster templates
// store w = 0 vertices as the polygon vertex itself and get the direction away from the light
// here (light.w = 1); the silhouette pass writes directions already (light.w = 0). With the
// infinite-far projection a w = 0 vertex lands exactly on depth 1; without depth clamp it is
// nudged just inside the far plane so rounding can never clip the far cap.
#include "common/frame.glsl"

layout(location = 0) in vec4 in_position;

layout(push_constant) uniform Volume {
    vec4 light;     // xyz: light position; w: 1 to subtract it from w = 0 vertices
    uint nudge_far; // 1 when the pipeline has no depth clamp
} volume;

const float NEAR_CAP_DEPTH_OFFSET = 1.0 / 1048576.0;

void main() {
    vec4 v = in_position;
    bool cap = v.w == 2.0;
    if (cap) {
        v.w = 1.0;
    }
    if (v.w == 0.0) {
        v.xyz -= volume.light.xyz * volume.light.w;
    }
    vec4 clip = frame.view_proj * v;
    if (cap) {
        clip.z += NEAR_CAP_DEPTH_OFFSET * clip.w;
    }
    if (volume.nudge_far != 0u && v.w == 0.0) {
        clip.z = clip.w * (1.0 - 1.0 / 1048576.0);
    }
    gl_Position = clip;
}
