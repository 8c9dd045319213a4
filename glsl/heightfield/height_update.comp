#version 460
// Height update (the height-field thesis section 1.10): evaluates the scene's generator (or resamples its
// height image) at this frame's time into the level-0 height image, metres.
#include "heightfield/generate.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform Gen { HfGen g; } gen;
layout(set = 0, binding = 1) uniform sampler2D source_image;
layout(set = 0, binding = 2, r32f) uniform writeonly image2D heights_out;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    int res = int(gen.g.field.y);
    if (p.x >= res || p.y >= res) return;
    float s = gen.g.field.x / float(res);
    float x = -0.5 * gen.g.field.x + (float(p.x) + 0.5) * s;
    float z = -0.5 * gen.g.field.x + (float(p.y) + 0.5) * s;
    imageStore(heights_out, p, vec4(hf_height(gen.g, x, z, source_image), 0.0, 0.0, 0.0));
}
