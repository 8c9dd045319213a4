#!/usr/bin/env bash
# The measurements that need a real GPU, in one run, on whatever device penumbra picks (a
# discrete GPU when there is one), each step under its own time limit so that one slow step
# costs only itself. Results go to OUTDIR (the log is printed); with a second argument, OUTDIR
# is packed into that .tar.gz after every step, so whatever finished survives a run that is cut
# short.
#
#   cargo build --release && tools/gpu_bench.sh [--quick] [--full] OUTDIR [results.tar.gz]
#
# The targets (their step limits add up to 8.5 minutes, the build of the measurement tests
# before them aside):
#   - the radiosity GPU shooter against the CPU solve on the Cornell box at equal light-maps
#     (their difference printed; target: at least 5x faster);
#   - the SH light-map's GPU visibility ray caster against the CPU's, rays per second;
#   - the height-field horizon pyramid against the brute-force march at equal horizon error, at
#     256^2, 512^2 and 1024^2 (the seed's case for the pyramid);
#   - the Ca3D-Engine thesis's frame (bsp_rooms, `seed000`) and Dickson et al. 2011's (lpv_bush, `lpv_over_forward` at the
#     document's 16^3 and 32^3 volumes, 256^2 RSM) at the documents' window sizes, against their
#     published frame rates;
#   - the generated-scene suite, the first of four shards of the lavapipe table's scenes;
#   - shadow volumes on theatre_100 with the lights lit together and with a pass per light.
# The seed frames are raster-bound: on a data-centre part (H100, H200, A100, ...), whose
# rasterisation runs on few units, the script says so, and their frame-rate targets are to be
# judged on a graphics GPU.
#
# --quick runs every step at tiny sizes on lavapipe (the dev build, `cargo test` without
#   --release) to prove that each one runs; its numbers mean nothing.
# --full adds, after the targets, the earlier measurements (well over 8 minutes): the reference
#   against Mitsuba 3 (tools/reference_vs_mitsuba.py, when $PYTHON can import mitsuba) and alone
#   at 1024x1024; the PRT bakers side by side on prt_bunny_cow and prt_throughput and run-time
#   shading of 1,004,004 PRT vertices; frame time against 1 ... 4,096 lights for the five
#   many-light methods (tools/many_lights_scaling.py); every method family captured once under
#   the validation layer (when it is installed); charts of theatre_100, prt_bunny_cow and
#   terrain_sky; the 114,127-vertex PRT bake with each baker.
#
# Needs cargo (the radiosity, SH and horizon measurements are ignored tests, built first), python3
# (the scene variants, the frame-rate lines and the --full tools), a TrueType font for the
# --full charts (fonts-dejavu-core); vulkaninfo and the validation layer are used when present.
# The results of its runs on an NVIDIA H200 are kept as data in docs/results/h200/
# (docs/results/README.md).
set -uo pipefail
cd "$(dirname "$0")/.."
quick=0
full=0
while [ $# -gt 0 ]; do
    case $1 in
    --quick) quick=1 ;;
    --full) full=1 ;;
    *) break ;;
    esac
    shift
done
out=${1:?usage: tools/gpu_bench.sh [--quick] [--full] OUTDIR [PACK.tar.gz]}
pack=${2:-}
target_dir=${CARGO_TARGET_DIR:-target}
if [ "$quick" = 1 ]; then
    profile_dir=debug
    export cargo_release=""
    export PENUMBRA_DEVICE_NAME=${PENUMBRA_DEVICE_NAME:-llvmpipe}
else
    profile_dir=release
    export cargo_release=--release
fi
bin=$(realpath "${PENUMBRA:-$target_dir/$profile_dir/penumbra}")
py=${PYTHON:-python3}
mkdir -p "$out"
out=$(realpath "$out")
export bin py out
export PENUMBRA_CACHE="$out/cache"
# The scene variants live beside the shipped scenes (their asset paths are relative); none is
# left behind when a step is cut short.
trap 'rm -f scenes/_gpu_*.toml' EXIT

# The binary's device: PENUMBRA_DEVICE_NAME when set (passed as --device), else its own pick.

# Runs a command or one of the functions below (exported, run by a child bash) under `limit`
# seconds; timeout ends the whole process group.
step() {
    local limit=$1 name=$2
    shift 2
    # lavapipe on a shared CPU: three times the GPU's limits.
    if [ "$quick" = 1 ]; then limit=$((3 * limit)); fi
    echo "== $name (limit ${limit} s, $(date -u +%T) UTC)"
    local t0=$SECONDS
    timeout "$limit" bash -c '"$@"' step "$@"
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

# A frame's median time from `penumbra profile --json`, as a frame rate beside the published one.
frame_rate() {
    local label=$1 scene=$2 method=$3 size=$4 frames=$5 published=$6 json
    json="$out/profile_$(echo "$label" | tr -c 'A-Za-z0-9' _).json"
    "$bin" profile "$scene" --method "$method" --size "$size" --frames "$frames" --json "$json" \
        ${PENUMBRA_DEVICE_NAME:+--device "$PENUMBRA_DEVICE_NAME"} || return
    "$py" - "$json" "$label" "$published" "$raster_note" <<'PY'
import json, sys
path, label, published, note = sys.argv[1:]
r = json.load(open(path))
ms = next(p["median_ms"] for p in r["passes"] if p["name"] == "frame")
print(f"{label}: median frame {ms:.2f} ms = {1000 / ms:.1f} FPS at {r['width']}x{r['height']} on {r['device']}; published: {published}{note}")
PY
}

# An ignored measurement test of the `methods` test binary (built before the clock starts),
# module::name, its output kept in OUTDIR too.
measure() {
    cargo test $cargo_release --test methods -- --ignored --nocapture --exact "$1::$2" 2>&1 | tee "$out/$2${3:-}.txt"
}
export -f frame_rate measure

step 10 "device" "$bin" info ${PENUMBRA_DEVICE_NAME:+--device "$PENUMBRA_DEVICE_NAME"}
device=$("$bin" info ${PENUMBRA_DEVICE_NAME:+--device "$PENUMBRA_DEVICE_NAME"} 2>/dev/null | sed -n 's/^device  *//p' | head -n 1)
export PENUMBRA_MEASURE_DEVICE=${PENUMBRA_DEVICE_NAME:-$device}
export raster_note=""
if echo "$device" | grep -Eq 'H100|H200|H800|H20|A100|A800|A30|B100|B200|GH200|GB200'; then
    raster_note=" (NOTE: $device is a data-centre part with few rasterisation units: this raster-bound frame needs a graphics GPU to judge its target)"
    echo "== NOTE: $device is a data-centre part. The seed frames and the suite are raster-bound; their frame-rate targets need a graphics GPU (a GeForce, RTX or Radeon): numbers here are not evidence either way."
fi
echo "== build: the measurement tests (not timed)"
cargo test $cargo_release --no-run --test methods 2>&1 | tail -n 1

# The radiosity GPU shooter against the CPU solve, same light-map (target: at least 5x).
if [ "$quick" = 1 ]; then export RADIOSITY_MEASURE_SIZES=0.4; fi
step 50 "radiosity: GPU shooter against the CPU solve, Cornell box (target >= 5x)" measure radiosity_gpu measure_bake_time_against_patch_count

# The SH light-map's visibility rays on the GPU against the CPU.
if [ "$quick" = 1 ]; then export SH_MEASURE_PATCH=0.25 SH_MEASURE_SAMPLES=256; fi
step 40 "SH light-map: GPU ray caster against the CPU, rays per second" measure sh_lightmap_gpu measure_visibility_rays_per_second

# The horizon pyramid against the brute-force march at equal horizon error (mountains, city).
if [ "$quick" = 1 ]; then resolutions=(16 32 64); else resolutions=(256 512 1024); fi
limits=(25 60 90)
for k in 0 1 2; do
    export HF_MEASURE_RESOLUTIONS=${resolutions[$k]} PENUMBRA_MEASURE_OUT="$out/horizon_${resolutions[$k]}"
    step "${limits[$k]}" "horizon pyramid against brute force at ${resolutions[$k]}^2, equal horizon error" measure heightfield_measure speedup_at_equal_horizon_error "_${resolutions[$k]}"
done
unset HF_MEASURE_RESOLUTIONS PENUMBRA_MEASURE_OUT

# The seeds' frames at the documents' window sizes, against their published frame rates.
if [ "$quick" = 1 ]; then
    seed000_size=64x48 small=64x64 large=96x96 frames=3 sv_size=64x48 lpv_small='grid = 8, rsm = 64' lpv_large='grid = 8, rsm = 64'
else
    seed000_size=1024x768 small=512x512 large=1024x1024 frames=100 sv_size=640x360 lpv_small='grid = 16, rsm = 256' lpv_large='grid = 32, rsm = 256'
fi
step 45 "seed 000's light-map bake (before its frame; not frame time)" "$bin" bake scenes/bsp_rooms.toml --method seed000 \
    ${PENUMBRA_DEVICE_NAME:+--device "$PENUMBRA_DEVICE_NAME"}
step 30 "seed 000's frame (bsp_rooms, seed000)" frame_rate "seed 000 frame" scenes/bsp_rooms.toml seed000 "$seed000_size" "$frames" \
    "20+ FPS 'interactive' (section 4.5.1); 27-37 FPS on NV2X with the PVS (Table 2; the document gives no window size, 1024x768 is assumed)"
lpv_bush() {
    variant scenes/lpv_bush.toml "scenes/_gpu_lpv_$1.toml" "\"forward\", { name = \"lpv\", centre = [0.0, 1.2, 0.0], size = 3.2, gbuffer = 128, $2 }"
}
lpv_bush small "$lpv_small"
lpv_bush large "$lpv_large"
step 30 "seed 004's frame, 512x512, 256^2 RSM, 16^3 LPV" frame_rate "seed 004 frame 512x512 16^3" scenes/_gpu_lpv_small.toml lpv_over_forward "$small" "$frames" \
    "52.73 FPS on a GeForce 9800GT (Table 5.1, 256^2 RSM, 16^3); the report's bar is 30 FPS"
step 30 "seed 004's frame, 1024x1024, 256^2 RSM, 16^3 LPV" frame_rate "seed 004 frame 1024x1024 16^3" scenes/_gpu_lpv_small.toml lpv_over_forward "$large" "$frames" \
    "37.24 FPS on a GeForce 9800GT (Table 5.2, 256^2 RSM, 16^3)"
step 30 "seed 004's frame, 1024x1024, 256^2 RSM, 32^3 LPV (the qualitative configuration)" frame_rate "seed 004 frame 1024x1024 32^3" scenes/_gpu_lpv_large.toml lpv_over_forward "$large" "$frames" \
    "29.00 FPS on a GeForce 9800GT (Table 5.2, 256^2 RSM, 32^3)"
rm -f scenes/_gpu_lpv_*.toml

# The generated-scene suite: the first of four shards of the table in docs/results/lavapipe
# (seed 1, 32x24, 256 spp references, every method each scene declares), so that the two
# devices' rows compare scene by scene; its CSV and summary go to OUTDIR/suite.
step 35 "generated-scene suite, shard 1/4 of seed 1" "$bin" suite --scenes 12 --seed 1 --size 32x24 \
    --supersample 2 --reference-spp 256 --shard 1/4 -o "$out/suite" --cache-dir "$out/cache"
# Shadow volumes with the lights that reach everything in view lit together (one pass over the
# receivers per 96) against a pass per light, as the thesis draws them: on lavapipe the grouped
# pass took the atrium's 17-lamp frame from 2.37 s to 1.47 s; on a GPU, where a light pass costs
# little, the 96-light loop per pixel may not pay.
for group in true false; do
    variant scenes/theatre_100.toml "scenes/_gpu_sv_group_$group.toml" \
        "{ name = \"shadow_volumes\", mode = \"physical\", group_lights = $group }"
    step 15 "shadow volumes, theatre_100, group_lights = $group" frame_rate "shadow volumes group_lights=$group" \
        "scenes/_gpu_sv_group_$group.toml" shadow_volumes "$sv_size" "$frames" "(none: the two against each other)"
done
rm -f scenes/_gpu_sv_group_*.toml
echo "== targets done ($(date -u +%T) UTC)"
[ "$full" = 1 ] || exit 0

if command -v vulkaninfo >/dev/null; then
    step 30 "ray query" bash -c 'vulkaninfo 2>/dev/null | grep -E "deviceName|driverInfo|VK_KHR_ray_query|VK_KHR_acceleration_structure|VK_KHR_ray_tracing_pipeline" | sort -u'
fi

# The reference's rate, beside Mitsuba's on the same machine.
if "$py" -c 'import mitsuba, numpy' 2>/dev/null; then
    step 240 "reference against Mitsuba 3, 256x256" "$py" tools/reference_vs_mitsuba.py --penumbra "$bin" --size 256x256 --spp-scale 4 --variants scalar_rgb,cuda_ad_rgb
else
    echo "== reference against Mitsuba 3: skipped ($py cannot import mitsuba and numpy)"
fi
step 60 "reference, Cornell box, 32 bounces, 1024x1024" "$bin" reference scenes/cornell.toml --size 1024x1024 --spp 64 --bounces 32 -o "$out/cornell_1024.exr"
step 60 "reference, furnace, 1024x1024" "$bin" reference scenes/furnace.toml --size 1024x1024 --spp 16 -o "$out/furnace_1024.exr"

# Bake throughput of each PRT baker on the same 7,915 vertices, and run-time shading.
prt_bake() {
    local name=$1 decl=$2 limit=$3 scene=${4:-prt_bunny_cow}
    variant "scenes/$scene.toml" "scenes/_gpu_$name.toml" "$decl"
    step "$limit" "PRT bake $scene: $decl" "$bin" bake "scenes/_gpu_$name.toml" --method prt
    rm -f "scenes/_gpu_$name.toml"
}
prt_bake cpu_rays '{ name = "prt", baker = "rays_cpu", samples = 1024 }' 60
prt_bake gpu_rays '{ name = "prt", baker = "rays", samples = 1024 }' 60
# The CPU and compute ray bakers alternating, three runs each after one compute bake that fills
# the driver's pipeline cache: the ratio the compute baker's target names. Machines differ (the
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

# Frame time against the number of lights, one run.
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

# PRT at scale: 114,127 vertices, 226k triangles.
prt_bake big_cpu_rays '{ name = "prt", baker = "rays_cpu", samples = 1024 }' 120 prt_throughput
prt_bake big_gpu_rays '{ name = "prt", baker = "rays", samples = 1024 }' 120 prt_throughput
prt_bake big_raster '{ name = "prt", baker = "raster", coverage = "exact", reduction = "compute" }' 300 prt_throughput
echo "== done ($(date -u +%T) UTC)"
