// Check kernel for the per-frame upload blocks (src/backend/descriptors.rs): one dispatch per
// uploaded block of words; invocation i of dispatch `slot` writes the word at i * stride of the
// block to result.values[slot * 64 + i], so the host sees whether the data the GPU read is what
// it uploaded, wherever the block landed. Not used by the renderer.
#version 460

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Data { uint words[]; } data;
layout(std430, set = 0, binding = 1) buffer Result { uint values[]; } result;
layout(push_constant) uniform Push { uint slot; uint stride; } push;

void main() {
    uint i = gl_GlobalInvocationID.x;
    result.values[push.slot * 64u + i] = data.words[i * push.stride];
}
