#version 460
// One propagation step, one invocation per destination cell (digest section 2.7).
// Corrected (Kaplanyan & Dachsbacher 2010): from each of the 6 face neighbours, the flux
// Omega_f * I_src(w_f) through the 5 faces of this cell that do not touch the source,
// reprojected as a cosine lobe toward the face, attenuated by the geometry volume between the
// cells; the new wavefront is written and added to the accumulation.
// Faithful (the document's volumeProp.glsl): 18 neighbours, delta lobes, 0.65 (edges x0.5),
// the sum /18 added to the cell's previous value.
#include "lpv/volume.glsl"

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(constant_id = 0) const uint FAITHFUL = 0u;
layout(constant_id = 1) const uint CLAMP = 1u;
layout(constant_id = 2) const uint OCCLUSION = 1u;
layout(constant_id = 3) const float OMEGA_FRONT = 0.4006696846;
layout(constant_id = 4) const float OMEGA_SIDE = 0.4234313544;

layout(set = 0, binding = 1) readonly buffer Source { uint w[]; } source;
layout(set = 0, binding = 2) writeonly buffer Destination { uint w[]; } destination;
layout(set = 0, binding = 3) buffer Accumulation { uint w[]; } accumulation;
// The geometry volume at each cell's three low faces (blocking_faces.comp).
layout(set = 0, binding = 4) readonly buffer Faces { vec4 b[]; } faces;

const ivec3 AXES[6] = ivec3[6](ivec3(1, 0, 0), ivec3(-1, 0, 0), ivec3(0, 1, 0), ivec3(0, -1, 0), ivec3(0, 0, 1), ivec3(0, 0, -1));

// The 30 faces crossed from the 6 face neighbours (generated: for each axis d, the front face
// then the side faces toward the 4 axes perpendicular to d in the order +x -x +y -y +z -z):
// the direction from the source cell's centre through the face, and the face's normal.
const vec3 FACE_DIRECTION[30] = vec3[30](
    vec3(1.0, 0.0, 0.0),
    vec3(0.894427191, 0.447213595, 0.000000000),
    vec3(0.894427191, -0.447213595, 0.000000000),
    vec3(0.894427191, 0.000000000, 0.447213595),
    vec3(0.894427191, 0.000000000, -0.447213595),
    vec3(-1.0, 0.0, 0.0),
    vec3(-0.894427191, 0.447213595, 0.000000000),
    vec3(-0.894427191, -0.447213595, 0.000000000),
    vec3(-0.894427191, 0.000000000, 0.447213595),
    vec3(-0.894427191, 0.000000000, -0.447213595),
    vec3(0.0, 1.0, 0.0),
    vec3(0.447213595, 0.894427191, 0.000000000),
    vec3(-0.447213595, 0.894427191, 0.000000000),
    vec3(0.000000000, 0.894427191, 0.447213595),
    vec3(0.000000000, 0.894427191, -0.447213595),
    vec3(0.0, -1.0, 0.0),
    vec3(0.447213595, -0.894427191, 0.000000000),
    vec3(-0.447213595, -0.894427191, 0.000000000),
    vec3(0.000000000, -0.894427191, 0.447213595),
    vec3(0.000000000, -0.894427191, -0.447213595),
    vec3(0.0, 0.0, 1.0),
    vec3(0.447213595, 0.000000000, 0.894427191),
    vec3(-0.447213595, 0.000000000, 0.894427191),
    vec3(0.000000000, 0.447213595, 0.894427191),
    vec3(0.000000000, -0.447213595, 0.894427191),
    vec3(0.0, 0.0, -1.0),
    vec3(0.447213595, 0.000000000, -0.894427191),
    vec3(-0.447213595, 0.000000000, -0.894427191),
    vec3(0.000000000, 0.447213595, -0.894427191),
    vec3(0.000000000, -0.447213595, -0.894427191));
const vec3 FACE_NORMAL[30] = vec3[30](
    vec3(1.0, 0.0, 0.0),
    vec3(0.0, 1.0, 0.0),
    vec3(0.0, -1.0, 0.0),
    vec3(0.0, 0.0, 1.0),
    vec3(0.0, 0.0, -1.0),
    vec3(-1.0, 0.0, 0.0),
    vec3(0.0, 1.0, 0.0),
    vec3(0.0, -1.0, 0.0),
    vec3(0.0, 0.0, 1.0),
    vec3(0.0, 0.0, -1.0),
    vec3(0.0, 1.0, 0.0),
    vec3(1.0, 0.0, 0.0),
    vec3(-1.0, 0.0, 0.0),
    vec3(0.0, 0.0, 1.0),
    vec3(0.0, 0.0, -1.0),
    vec3(0.0, -1.0, 0.0),
    vec3(1.0, 0.0, 0.0),
    vec3(-1.0, 0.0, 0.0),
    vec3(0.0, 0.0, 1.0),
    vec3(0.0, 0.0, -1.0),
    vec3(0.0, 0.0, 1.0),
    vec3(1.0, 0.0, 0.0),
    vec3(-1.0, 0.0, 0.0),
    vec3(0.0, 1.0, 0.0),
    vec3(0.0, -1.0, 0.0),
    vec3(0.0, 0.0, -1.0),
    vec3(1.0, 0.0, 0.0),
    vec3(-1.0, 0.0, 0.0),
    vec3(0.0, 1.0, 0.0),
    vec3(0.0, -1.0, 0.0));

void corrected(ivec3 x, uint cell) {
    vec4 acc[3] = vec4[3](vec4(0.0), vec4(0.0), vec4(0.0));
    for (int a = 0; a < 6; ++a) {
        ivec3 d = AXES[a];
        ivec3 s = x - d;
        if (!inside(s)) {
            continue;
        }
        uint sc = cell_index(s);
        vec4 src[3] = vec4[3](SET_LOAD(source, slot(sc, 0u)), SET_LOAD(source, slot(sc, 1u)), SET_LOAD(source, slot(sc, 2u)));
        vec4 b = vec4(0.0);
        if (OCCLUSION != 0u) {
            // The face between the cells is the low face, on d's axis, of the one further along d.
            int axis = a / 2;
            b = faces.b[cell_index((a & 1) == 0 ? x : s) * 3u + uint(axis)];
        }
        for (int f = 0; f < 5; ++f) {
            vec3 dir = FACE_DIRECTION[a * 5 + f];
            vec4 y = sh_basis(dir);
            float transmit = 1.0;
            if (OCCLUSION != 0u) {
                transmit = 1.0 - clamp(dot(b, sh_basis(-dir)), 0.0, 1.0);
            }
            vec4 lobe = cosine_lobe(FACE_NORMAL[a * 5 + f]) * ((f == 0 ? OMEGA_FRONT : OMEGA_SIDE) / SH_PI * transmit);
            for (uint ch = 0u; ch < 3u; ++ch) {
                float intensity = dot(src[ch], y);
                if (CLAMP != 0u) {
                    intensity = max(intensity, 0.0);
                }
                acc[ch] += intensity * lobe;
            }
        }
    }
    for (uint ch = 0u; ch < 3u; ++ch) {
        uint s = slot(cell, ch);
        SET_STORE(destination, s, acc[ch]);
        vec4 total = SET_LOAD(accumulation, s) + acc[ch];
        SET_STORE(accumulation, s, total);
    }
}

void faithful(ivec3 x, uint cell) {
    vec4 acc[3] = vec4[3](vec4(0.0), vec4(0.0), vec4(0.0));
    for (int k = 0; k < 18; ++k) {
        ivec3 o;
        float w;
        if (k < 6) {
            o = AXES[k];
            w = 1.0;
        } else {
            // The 12 edge neighbours: two non-zero components of +-1.
            int e = k - 6;
            int pair = e / 4;
            int signs = e % 4;
            ivec2 sg = ivec2((signs & 1) == 0 ? 1 : -1, (signs & 2) == 0 ? 1 : -1);
            o = pair == 0 ? ivec3(sg.x, sg.y, 0) : (pair == 1 ? ivec3(sg.x, 0, sg.y) : ivec3(0, sg.x, sg.y));
            w = 0.5;
        }
        ivec3 n = x + o;
        if (!inside(n)) {
            continue;
        }
        uint nc = cell_index(n);
        vec3 dir = -normalize(vec3(o));
        vec4 y = sh_basis(dir);
        for (uint ch = 0u; ch < 3u; ++ch) {
            float l = max(dot(SET_LOAD(source, slot(nc, ch)), y), 0.0);
            acc[ch] += y * (0.65 * w * l);
        }
    }
    for (uint ch = 0u; ch < 3u; ++ch) {
        uint s = slot(cell, ch);
        vec4 v = acc[ch] / 18.0 + SET_LOAD(source, s);
        SET_STORE(destination, s, v);
    }
}

void main() {
    ivec3 x = ivec3(gl_GlobalInvocationID);
    if (!inside(x)) {
        return;
    }
    uint cell = cell_index(x);
    if (FAITHFUL != 0u) {
        faithful(x, cell);
    } else {
        corrected(x, cell);
    }
}
