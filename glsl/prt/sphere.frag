#version 460
// The colour-coded sphere's angles into R and G of the visibility atlas (the pipeline writes
// only R and G; B holds the visibility). Only the front hemisphere.

layout(constant_id = 2) const int TILE = 32;

layout(location = 0) in vec2 in_colour;
layout(location = 1) in float in_front;
layout(location = 2) flat in ivec2 in_tile;

layout(location = 0) out vec4 out_atlas;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    if (any(lessThan(p, in_tile)) || any(greaterThanEqual(p, in_tile + TILE)) || in_front <= 0.0) {
        discard;
    }
    out_atlas = vec4(in_colour, 0.0, 0.0);
}
