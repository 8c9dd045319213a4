#version 460
// The geometry volume at the faces between cells, once per frame before the propagation: for
// each cell and axis, the blocking potential at the centre of the cell's face on the low side
// of that axis. The face lies on a plane of the volume's corners, so it is the mean of the 4
// corners around it (zero outside). The propagation then reads one value per neighbour.
#include "lpv/volume.glsl"

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(set = 0, binding = 1) readonly buffer Blocking { vec4 b[]; } blocking;
layout(set = 0, binding = 2) writeonly buffer Faces { vec4 b[]; } faces;

vec4 corner(ivec3 c) {
    return inside(c) ? blocking.b[cell_index(c)] : vec4(0.0);
}

void main() {
    ivec3 x = ivec3(gl_GlobalInvocationID);
    if (!inside(x)) {
        return;
    }
    uint cell = cell_index(x);
    const ivec3 E[3] = ivec3[3](ivec3(1, 0, 0), ivec3(0, 1, 0), ivec3(0, 0, 1));
    for (int axis = 0; axis < 3; ++axis) {
        ivec3 u = E[(axis + 1) % 3];
        ivec3 v = E[(axis + 2) % 3];
        faces.b[cell * 3u + uint(axis)] = 0.25 * (corner(x) + corner(x + u) + corner(x + v) + corner(x + u + v));
    }
}
