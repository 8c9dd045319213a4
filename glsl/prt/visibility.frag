#version 460
// Phase 1's occluder value (src/lighting/prt/raster.rs): 0, or with the distance gradient of
// the document's section 3.1 the depth (0 at near, 1 at far). The atlas is cleared to 1.

layout(constant_id = 1) const int RADIAL = 0;
layout(constant_id = 2) const int TILE = 32;
layout(constant_id = 7) const float NEAR = 0.001;
layout(constant_id = 9) const int GRADIENT = 0;

layout(location = 0) in float in_front;
layout(location = 1) flat in ivec2 in_tile;

// The atlas is RGBA: the pipeline writes only B (R and G are the colour-coded sphere's).
layout(location = 0) out vec4 out_atlas;

void main() {
    // A triangle projected across its tile's border belongs to this tile only.
    ivec2 p = ivec2(gl_FragCoord.xy);
    if (any(lessThan(p, in_tile)) || any(greaterThanEqual(p, in_tile + TILE))) {
        discard;
    }
    // Radial depth clipped each triangle to the hemisphere in visibility.vert; what is left in
    // the tangent plane itself (a triangle around the vertex, whose corner at the vertex
    // projects to the tile's centre) would cover a wedge out to the horizon.
    if (RADIAL == 1 && in_front <= max(NEAR * 0.01, 1e-7)) {
        discard;
    }
    out_atlas = vec4(0.0, 0.0, GRADIENT == 1 ? clamp(gl_FragCoord.z, 0.0, 1.0) : 0.0, 0.0);
}
