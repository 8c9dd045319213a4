#!/usr/bin/env bash
# The measurements that need a real GPU (issues 11, 14 and 15), in one run, on whatever device
# penumbra picks (a discrete GPU when there is one), most important first, each step under its
# own time limit so that one slow step costs only itself. Results go to OUTDIR (the log is
# printed); with a second argument, OUTDIR is packed into that .tar.gz after every step, so
# whatever finished survives a run that is cut short.
#
#   cargo build --release && tools/gpu_bench.sh /tmp/gpu-results [results.tar.gz]
#
# Steps: the device (and whether it has VK_KHR_ray_query, from vulkaninfo when present); the
# reference against Mitsuba 3 (tools/reference_vs_mitsuba.py, when $PYTHON can import mitsuba;
# with the cuda_ad_rgb variant beside the CPU ones) and the reference alone at 1024x1024; the PRT
# bakers side by side on prt_bunny_cow (CPU rays on every core, compute rays, the two ray bakers
# alternating there and on prt_throughput, the raster baker's three paths) and run-time shading of 1,004,004 PRT vertices; frame time against 1 ... 4,096
# lights for the five many-light methods (tools/many_lights_scaling.py); every method family
# captured once under the validation layer (when it is installed); charts of theatre_100,
# prt_bunny_cow and terrain_sky; the 114,127-vertex PRT bake with each baker.
#
# Needs python3 (the scene variants and the two tools), a TrueType font for the charts
# (fonts-dejavu-core); vulkaninfo and the validation layer are used when present. The results of
# its runs on an NVIDIA H200 are kept as data in docs/results/h200/ (docs/results/README.md).
set -uo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: tools/gpu_bench.sh OUTDIR [PACK.tar.gz]}
pack=${2:-}
bin=$(realpath "${PENUMBRA:-target/release/penumbra}")
py=${PYTHON:-python3}
mkdir -p "$out"
export PENUMBRA_CACHE="$out/cache"
# The scene variants live beside the shipped scenes (their asset paths are relative); none is
# left behind when a step is cut short.
trap 'rm -f scenes/_gpu_*.toml' EXIT

step() {
    local limit=$1 name=$2
    shift 2
    echo "== $name (limit ${limit} s, $(date -u +%T) UTC)"
    local t0=$SECONDS
    timeout "$limit" "$@"
    echo "== $name: exit $?, $((SECONDS - t0)) s"
    if [ -n "$pack" ]; then tar -czf "$pack" -C "$out" --exclude=cache --exclude='*.exr' . 2>/dev/null; fi
}

# A copy of a scene with its methods line replaced, next to the original (relative asset paths).
variant() {
    "$py" - "$1" "$2" "$3" <<'PY'
import re, sys
src, dst, methods = sys.argv[1:]
text = open(src).read()
text = re.sub(r"(?ms)^methods = \[\s*\n.*?^\]\n|^methods = \[[^\n]*\]\n", "", text, count=1)
open(dst, "w").write("methods = [ %s ]\n" % methods + text)
PY
}

step 30 "device" "$bin" info
if command -v vulkaninfo >/dev/null; then
    step 30 "ray query" bash -c 'vulkaninfo 2>/dev/null | grep -E "deviceName|driverInfo|VK_KHR_ray_query|VK_KHR_acceleration_structure|VK_KHR_ray_tracing_pipeline" | sort -u'
fi

# Issue 11: the reference's rate, beside Mitsuba's on the same machine.
if "$py" -c 'import mitsuba, numpy' 2>/dev/null; then
    step 240 "reference against Mitsuba 3, 256x256" "$py" tools/reference_vs_mitsuba.py --penumbra "$bin" --size 256x256 --spp-scale 4 --variants scalar_rgb,cuda_ad_rgb
else
    echo "== reference against Mitsuba 3: skipped ($py cannot import mitsuba and numpy)"
fi
step 60 "reference, Cornell box, 32 bounces, 1024x1024" "$bin" reference scenes/cornell.toml --size 1024x1024 --spp 64 --bounces 32 -o "$out/cornell_1024.exr"
step 60 "reference, furnace, 1024x1024" "$bin" reference scenes/furnace.toml --size 1024x1024 --spp 16 -o "$out/furnace_1024.exr"

# Issue 14: bake throughput of each PRT baker on the same 7,915 vertices, and run-time shading.
prt_bake() {
    local name=$1 decl=$2 limit=$3 scene=${4:-prt_bunny_cow}
    variant "scenes/$scene.toml" "scenes/_gpu_$name.toml" "$decl"
    step "$limit" "PRT bake $scene: $decl" "$bin" bake "scenes/_gpu_$name.toml" --method prt
    rm -f "scenes/_gpu_$name.toml"
}
prt_bake cpu_rays '{ name = "prt", baker = "rays_cpu", samples = 1024 }' 60
prt_bake gpu_rays '{ name = "prt", baker = "rays", samples = 1024 }' 60
# The CPU and compute ray bakers alternating, three runs each after one compute bake that fills
# the driver's pipeline cache: the ratio issue 14's target names. Lease machines differ (the
# CPU rays of one bake took 377-691 ms on three of them), so only ratios within one run count.
prt_alternate() {
    local scene=$1
    variant "scenes/$scene.toml" scenes/_gpu_alt_cpu.toml '{ name = "prt", baker = "rays_cpu", samples = 1024 }'
    variant "scenes/$scene.toml" scenes/_gpu_alt_gpu.toml '{ name = "prt", baker = "rays", samples = 1024 }'
    for side in gpu cpu gpu cpu gpu cpu gpu; do
        rm -rf "$PENUMBRA_CACHE/bake"
        step 60 "PRT bake $scene, $side rays, alternating" "$bin" bake "scenes/_gpu_alt_$side.toml" --method prt
    done
    rm -f scenes/_gpu_alt_*.toml
}
prt_alternate prt_bunny_cow
prt_alternate prt_throughput
prt_bake raster_compute '{ name = "prt", baker = "raster", coverage = "exact", reduction = "compute" }' 120
prt_bake raster_passes '{ name = "prt", baker = "raster", coverage = "exact", reduction = "passes" }' 120
prt_bake raster_projected '{ name = "prt", baker = "raster", coverage = "projected", reduction = "passes" }' 120
prt_bake faithful '{ name = "prt", mode = "faithful" }' 120
cat >scenes/_gpu_prt_million.toml <<'EOF'
# 1,004,004 PRT vertices: four 500-subdivision planes side by side (run-time shading cost).
methods = [ { name = "prt", baker = "rays", samples = 64 }, "forward" ]
[camera]
position = [0.0, 6.0, 9.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 50
[environment]
type = "image"
path = "terrain/sky.hdr"
[[materials]]
name = "floor"
albedo = 0.6
EOF
for x in -4.5 -1.5 1.5 4.5; do
    printf '[[objects]]\nname = "plane%s"\nmesh = "plane"\nsize = 3\nsubdivisions = 500\nmaterial = "floor"\ntranslate = [%s, 0, 0]\n' "$x" "$x" >>scenes/_gpu_prt_million.toml
done
step 120 "PRT run-time shading, 1,004,004 vertices, 1280x720" "$bin" profile scenes/_gpu_prt_million.toml --method prt --size 1280x720 --frames 30
step 60 "forward on the same mesh, 1280x720" "$bin" profile scenes/_gpu_prt_million.toml --method forward --size 1280x720 --frames 30
rm -f scenes/_gpu_prt_million.toml

# Issue 15: frame time against the number of lights, one run.
step 300 "many lights, 1 ... 4,096, 1280x720" "$py" tools/many_lights_scaling.py --binary "$bin" --counts 1,4,16,64,256,1024,2048,4096 --frames 10 --size 1280x720 --timeout 60 --out "$out/many_lights_scaling_gpu"

# Zero validation messages on a real driver: every method family once.
if [ -n "$(ls /usr/share/vulkan/explicit_layer.d/*validation* 2>/dev/null)" ]; then
    for case in "scenes/default.toml" "scenes/bsp_rooms.toml seed000" "scenes/lpv_bush.toml lpv_over_forward" \
        "scenes/theatre_50.toml bsp_lights" "scenes/theatre_50.toml vls" "scenes/theatre_50.toml clustered" \
        "scenes/theatre_50.toml shadow_volumes" "scenes/prt_teapot_box.toml prt" "scenes/sh_courtyard.toml sh_lightmap" \
        "scenes/terrain_sky.toml heightfield_pyramid" "scenes/terrain_sky.toml heightfield_bruteforce"; do
        set -- $case
        step 90 "validation: $*" "$bin" capture "$1" ${2:+--method "$2"} --size 320x180 --frames 3 --validation -o "$out/validation_$(basename "$1" .toml)_${2:-default}.png"
    done
    step 60 "validation: reference" "$bin" reference scenes/cornell.toml --size 64x64 --spp 16 --validation -o "$out/validation_reference.exr"
fi

# Charts (time against error) on the GPU.
step 240 "chart theatre_100, 640x360" "$bin" chart scenes/theatre_100.toml --size 640x360 --cache-dir "$out/cache" -o "$out/chart_theatre_100.png" --csv "$out/chart_theatre_100.csv"
step 240 "chart prt_bunny_cow, 640x360" "$bin" chart scenes/prt_bunny_cow.toml --size 640x360 --cache-dir "$out/cache" -o "$out/chart_prt_bunny_cow.png" --csv "$out/chart_prt_bunny_cow.csv"
step 240 "chart terrain_sky at its defaults" "$bin" chart scenes/terrain_sky.toml --cache-dir "$out/cache" -o "$out/chart_terrain_sky.png" --csv "$out/chart_terrain_sky.csv"

# Issue 14 at scale: 114,127 vertices, 226k triangles.
prt_bake big_cpu_rays '{ name = "prt", baker = "rays_cpu", samples = 1024 }' 120 prt_throughput
prt_bake big_gpu_rays '{ name = "prt", baker = "rays", samples = 1024 }' 120 prt_throughput
prt_bake big_raster '{ name = "prt", baker = "raster", coverage = "exact", reduction = "compute" }' 300 prt_throughput
echo "== done ($(date -u +%T) UTC)"
