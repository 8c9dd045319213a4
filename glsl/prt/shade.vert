#version 460
// Run-time PRT shading (src/lighting/prt/mod.rs, Listing 2.8 per vertex): the vertex's transfer
// (two SH keys blended, Listing 3.1; one key for a static scene) dotted with the light's 16 RGB
// coefficients. Exit radiance is albedo / pi times this (shade.frag). The transfer is fp32 or the
// shared-exponent storage decoded here (layouts: storage.rs, pack_for_device).
#include "common/frame.glsl"
#define PENUMBRA_SCENE_VERTEX
#include "common/scene.glsl"

layout(set = 0, binding = 1) readonly buffer Transfer { uint words[]; } transfer;
layout(set = 0, binding = 2) readonly buffer Light {
    vec4 coeffs[16];  // rgb, zero past the coefficients in use
    uvec4 keys;       // x: first key, y: second key, z: vertices per key, w: coefficients in use
    vec4 blend;       // x: weight of the second key
    uvec4 storage;    // x: 0 fp32, 1 shared exponent by band, 2 by vertex; y: words per key
} light;

layout(location = 0) out vec3 out_irradiance;
layout(location = 1) out vec2 out_uv;
layout(location = 2) out vec3 out_normal;
layout(location = 3) out vec3 out_world;

const uint STORAGE_F32 = 0u;
const uint STORAGE_BY_BAND = 1u;

// Four signed 8-bit mantissas times 2^e / 128, e + 128 the exponent byte.
vec4 unpack_group(uint mantissas, uint exponent_byte) {
    vec4 m = vec4(bitfieldExtract(int(mantissas), 0, 8), bitfieldExtract(int(mantissas), 8, 8),
                  bitfieldExtract(int(mantissas), 16, 8), bitfieldExtract(int(mantissas), 24, 8));
    return m * exp2(float(exponent_byte) - 135.0);
}

// Coefficients 4g .. 4g + 3 of vertex v in key k.
vec4 coefficients(uint k, uint v, uint g) {
    uint key = k * light.storage.y;
    if (light.storage.x == STORAGE_F32) {
        uint w = key + v * 16u + g * 4u;
        return uintBitsToFloat(uvec4(transfer.words[w], transfer.words[w + 1u], transfer.words[w + 2u],
                                     transfer.words[w + 3u]));
    }
    if (light.storage.x == STORAGE_BY_BAND) {
        // Coefficient i of four vertices a word (byte v mod 4), then the 16 exponents.
        uint block = key + (v / 4u) * 20u;
        int lane = int(8u * (v % 4u));
        uint exponents = transfer.words[block + 16u + g];
        vec4 t;
        for (int c = 0; c < 4; ++c) {
            int m = bitfieldExtract(int(transfer.words[block + 4u * g + uint(c)]), lane, 8);
            t[c] = float(m) * exp2(float(bitfieldExtract(exponents, 8 * c, 8)) - 135.0);
        }
        return t;
    }
    // By vertex: the four groups' mantissas a word each, then their exponents.
    uint block = key + v * 5u;
    return unpack_group(transfer.words[block + g], bitfieldExtract(transfer.words[block + 4u], int(8u * g), 8));
}

void main() {
    vec4 world = draw.model * vec4(in_position, 1.0);
    uint v = uint(gl_VertexIndex);
    vec3 e = vec3(0.0);
    for (uint g = 0u; g < 4u; ++g) {
        vec4 t = mix(coefficients(light.keys.x, v, g), coefficients(light.keys.y, v, g), light.blend.x);
        for (int c = 0; c < 4; ++c) {
            e += t[c] * light.coeffs[4u * g + uint(c)].rgb;
        }
    }
    out_irradiance = e;
    out_uv = in_uv;
    out_normal = transpose(inverse(mat3(draw.model))) * in_normal;
    out_world = world.xyz;
    gl_Position = frame.view_proj * world;
}
