#version 460
// One light's bit in the grouped light pass's mask (light_group.frag): drawn over the whole
// target with the stencil test passing where the count is 0, i.e. outside every volume of the
// light, and added there. Each light of a group has its own bit, and each pixel is covered
// once, so the sums are exact.
layout(push_constant) uniform Slot {
    vec4 bit;  // 2^(k % 24) in channel k / 24, for light k of the group
} slot;

layout(location = 0) in vec2 in_uv;  // fullscreen.vert's, unused
layout(location = 0) out vec4 out_mask;

void main() {
    out_mask = slot.bit;
}
