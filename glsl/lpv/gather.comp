#version 460
// Gather injection, the document's volumeGen.glsl (digest section 2.5, Appendix 1): each cell samples
// the RSM at a few offsets of a 64-entry table (the same for every cell, at most 1/8 of a cell),
// keeps samples whose RSM depth lies within half a cell of the sample's, and averages delta
// lobes: the albedo along reflect(-L, N) and 0.75 x the albedo along L, times 4 pi over the
// number of lobes. With the transform bug (the document's listing) the volume-to-light
// transform is applied again to the accumulated sample position on every iteration.
#include "lpv/volume.glsl"

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(set = 0, binding = 1) uniform sampler2D rsm_flux;      // the document's mode: rgb albedo
layout(set = 0, binding = 2) uniform sampler2D rsm_position;  // xyz world position, a: 1 where drawn
layout(set = 0, binding = 3) uniform sampler2D rsm_normal;
layout(set = 0, binding = 4) readonly buffer Offsets { vec4 o[64]; } offsets;  // in [0, 1]
layout(set = 0, binding = 5) writeonly buffer Wavefront { uint w[]; } wavefront;

void main() {
    ivec3 x = ivec3(gl_GlobalInvocationID);
    if (!inside(x)) {
        return;
    }
    float n = float(volume.size.x);
    // Volume NDC, [-1, 1] across the cube, and the volume-to-light transform.
    vec4 voxel = vec4((vec3(x) + 0.5) / n * 2.0 - 1.0, 1.0);
    float extent = volume.origin.w * n;
    mat4 ndc_to_world = mat4(vec4(0.5 * extent, 0, 0, 0), vec4(0, 0.5 * extent, 0, 0), vec4(0, 0, 0.5 * extent, 0), vec4(volume.origin.xyz + 0.5 * extent, 1.0));
    mat4 volume_to_light = volume.light_view_proj * ndc_to_world;
    float window = 0.5 * volume.origin.w * volume.light_pos.w;
    vec4 sum[3] = vec4[3](vec4(0.0), vec4(0.0), vec4(0.0));
    float accepted = 0.0;
    vec4 sample_pos = voxel;
    int samples = min(volume.rsm.y, 64);
    for (int i = 0; i < samples; ++i) {
        vec4 offset = vec4((offsets.o[i].xyz * 2.0 - 1.0) / (4.0 * n), 0.0);
        vec4 p;
        if (volume.rsm.z != 0) {
            sample_pos += offset;
            sample_pos = volume_to_light * sample_pos;
            p = sample_pos;
        } else {
            p = volume_to_light * (voxel + offset);
        }
        p /= p.w;
        vec2 uv = p.xy * 0.5 + 0.5;
        if (any(lessThan(uv, vec2(0.0))) || any(greaterThanEqual(uv, vec2(1.0)))) {
            continue;
        }
        ivec2 t = ivec2(uv * float(volume.rsm.x));
        vec4 position = texelFetch(rsm_position, t, 0);
        if (position.w < 0.5) {
            continue;  // the document's sampledDepth != 0: the cleared background
        }
        vec4 texel = volume.light_view_proj * vec4(position.xyz, 1.0);
        if (abs(texel.z / texel.w - p.z) > window) {
            continue;
        }
        vec3 albedo = texelFetch(rsm_flux, t, 0).rgb;
        vec3 normal = normalize(texelFetch(rsm_normal, t, 0).xyz);
        vec3 l = volume.light.w > 0.5 ? normalize(position.xyz - volume.light_pos.xyz) : volume.light.xyz;
        vec4 bounce = sh_basis(reflect(-l, normal));
        vec4 through = sh_basis(l);
        for (int ch = 0; ch < 3; ++ch) {
            sum[ch] += albedo[ch] * bounce + 0.75 * albedo[ch] * through;
        }
        accepted += 2.0;
    }
    uint cell = cell_index(x);
    for (uint ch = 0u; ch < 3u; ++ch) {
        vec4 c = accepted > 0.0 ? 4.0 * SH_PI * sum[ch] / accepted * volume.scale.x : vec4(0.0);
        SET_STORE(wavefront, slot(cell, ch), c);
    }
}
