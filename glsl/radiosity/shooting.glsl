// Progressive-refinement shooting on the GPU (src/lighting/radiosity/gpu.rs): the records the
// three passes of a shot share, and their push constants. One shot is block_power.comp (every
// block's unshot power), select.comp (one workgroup picks the shooter, or says the solve is
// done) and shoot.comp (every receiver patch gathers its share, through a visibility ray).
#ifndef PENUMBRA_RADIOSITY_SHOOTING_GLSL
#define PENUMBRA_RADIOSITY_SHOOTING_GLSL

struct Patch {
    vec4 centre;  // xyz; w: the area of the surface inside the patch (0 for border patches)
    vec4 normal;  // xyz
    vec4 albedo;  // rgb
    uvec4 ids;    // x: chart, y: shooting block (NO_BLOCK for border patches), z: the sub-samples
                  // it keeps, bit 4*sj + si of its 4x4 grid (Patch::samples), w: 1 on a curved
                  // chart (its plane, step_u x step_v, is not its normal)
    vec4 first_sample;  // xyz: sub-sample (0, 0)
    vec4 step_u;        // xyz: from sub-sample (si, sj) to (si + 1, sj)
    vec4 step_v;        // xyz: from sub-sample (si, sj) to (si, sj + 1)
};

// Radiosity (W/m^2) of one patch, rgb: everything it emits and reflects, and what it has
// received but not shot yet.
struct Radiosity {
    vec4 total;
    vec4 unshot;
};

struct Block {
    uvec4 range;  // x: first member in `members`, y: member count, z: chart
    vec4 corners[4];
};

// The shot in progress, written by select.comp for shoot.comp.
struct Shot {
    vec4 centre;      // xyz: the block's area-weighted centre
    vec4 normal;      // xyz: its chart's normal
    vec4 flux;        // rgb: the unshot power it shoots (W)
    vec4 corners[4];  // its square
    vec4 size;        // x: the block's surface area, y: its square's area
    uvec4 state;      // x: block, y: 1 once the solve is done, z: full searches, w: unshot values logged
    uvec4 shots;      // x: shots taken, y: the shooting block's chart
};

const uint NO_BLOCK = 0xffffffffu;
const uint MODE_FAITHFUL = 0u;
const uint MODE_CORRECTED = 1u;

layout(push_constant) uniform Push {
    uint patch_count;
    uint block_count;
    uint chart_count;
    uint triangle_count;
    uint mode;
    uint samples_per_chart;
    float near_field;  // solve.rs NEAR_FIELD
    uint log_capacity;
    float stop;      // unshot power below which the solve stops (W)
    float epsilon;   // receivers and shooters start this far in front of their surface
    float patch_size;
    uint max_shots;
    uint visibility_matrix;  // 0: not built (too many charts), every pair PARTIAL
} push;

#endif
