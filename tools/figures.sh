#!/usr/bin/env bash
# Renders the method pages' figures: each configuration's image and its FLIP error map against
# the path tracer, into docs/images/, and writes their errors to
# docs/results/lavapipe/figures.csv (run `python3 tools/results_tables.py` after it).
#
#   bash tools/figures.sh [PENUMBRA_BINARY]
#
# The binary defaults to target/debug/penumbra (build it first). Bakes are built afresh in a
# private cache. A faithful variant renders a copy of its scene (written beside it, so its
# relative paths hold, and removed afterwards) whose method entry carries `mode = "faithful"`.
# About three minutes on lavapipe with two cores.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/debug/penumbra}
work=$(mktemp -d)
copies=()
trap 'rm -rf "$work"; rm -f "${copies[@]}"' EXIT
export PENUMBRA_CACHE="$work/cache"
export PENUMBRA_DEVICE_NAME="${PENUMBRA_DEVICE_NAME:-llvmpipe}"
mkdir -p docs/images

# figure | scene | size | reference | its flags | method | faithful variant (yes/no) | configuration
figures=(
  "theatre_vls_faithful|theatre_100|192x108|direct 64 spp|--direct-only|vls|yes|vls faithful (K = 8, closest, the thesis's feeler, OpenGL model)"
  "theatre_vls|theatre_100|192x108|direct 64 spp|--direct-only|vls|no|vls corrected (K = 32, derived; contribution)"
  "theatre_bsp_lights|theatre_100|192x108|direct 64 spp|--direct-only|bsp_lights|no|bsp_lights corrected"
  "theatre_forward|theatre_100|192x108|direct 64 spp|--direct-only|forward|no|forward (no shadows)"
  "bush_lpv|lpv_bush|128x96|indirect (1 bounce) 64 spp|--indirect-only --bounces 1|lpv|no|lpv corrected (as shipped)"
  "bush_lpv_faithful|lpv_bush|128x96|indirect (1 bounce) 64 spp|--indirect-only --bounces 1|lpv|yes|lpv faithful"
  "rad_corrected|cornell_radiosity|96x96|16 bounces 64 spp|--bounces 16|radiosity|no|radiosity corrected, 10 cm patches"
  "rad_faithful|cornell_radiosity|96x96|16 bounces 64 spp|--bounces 16|radiosity|yes|radiosity faithful, 10 cm patches"
  "rad_forward|cornell_radiosity|96x96|16 bounces 64 spp|--bounces 16|forward|no|forward (direct light only)"
  "city_pyramid|terrain_city|128x128|direct 64 spp|--direct-only|heightfield_pyramid|no|heightfield_pyramid (defaults)"
  "city_brute|terrain_city|128x128|direct 64 spp|--direct-only|heightfield_bruteforce|no|heightfield_bruteforce, 0.5-texel steps"
  "teapot_prt|prt_teapot_box|128x96|direct 64 spp|--direct-only|prt|no|prt corrected (defaults)"
  "teapot_prt_blackout|prt_teapot_box|128x96|direct 64 spp|--direct-only|prt_faithful|no|prt faithful, near = 0"
  "court_sh|sh_courtyard|128x96|16 bounces 64 spp|--bounces 16|sh_lightmap|no|sh_lightmap corrected, 4 bands"
  "court_radiosity|sh_courtyard|128x96|16 bounces 64 spp|--bounces 16|radiosity|no|radiosity corrected, 25 cm patches"
)

csv="$work/figures.csv"
commit=$(git rev-parse --short HEAD)
git diff --quiet HEAD -- src glsl scenes || commit="$commit (with uncommitted changes)"
"$bin" profile scenes/theatre_100.toml --method forward --size 16x16 --frames 1 --json "$work/device.json" > /dev/null 2>&1
field() { python3 -c "import json, sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$work/device.json" "$1"; }
cpu=$(lscpu | sed -n 's/^Model name: *//p' | head -1)
{
  echo "# device: $(field device) on a $(nproc)-core $cpu"
  echo "# driver: $(field driver)"
  echo "# commit: $commit"
  echo "# date: $(date +%F)"
  echo "# command: bash tools/figures.sh (per figure: penumbra reference SCENE --size WxH FLAGS --spp 64 -o ref.exr; penumbra capture SCENE --method M --size WxH -o M.png --exr M.exr; penumbra compare M.exr ref.exr --diff M_flip.png)"
  echo "# note: the images in docs/images/; the reference's own noise is included in each error"
  echo "figure,scene,size,reference,configuration,rel_mse,flip,mean_ratio"
} > "$csv"

for row in "${figures[@]}"; do
  IFS='|' read -r name scene size refname flags method faithful config <<< "$row"
  path="scenes/$scene.toml"
  ref="$work/${scene}_${size}_${refname// /_}.exr"
  if [ ! -f "$ref" ]; then
    # shellcheck disable=SC2086 # the flags are words
    "$bin" reference "$path" --size "$size" $flags --spp 64 -o "$ref" > /dev/null
  fi
  if [ "$faithful" = yes ]; then
    copy="scenes/.figure-$name-$$.toml"
    copies+=("$copy")
    sed -E "s/\{ *name = \"$method\"/{ name = \"$method\", mode = \"faithful\"/" "$path" > "$copy"
    grep -q "name = \"$method\", mode = \"faithful\"" "$copy" || {
      echo "figures: $path has no { name = \"$method\" ... } entry to make faithful" >&2
      exit 1
    }
    path="$copy"
  fi
  "$bin" capture "$path" --method "$method" --size "$size" -o "docs/images/$name.png" --exr "$work/$name.exr" > /dev/null
  out=$("$bin" compare "$work/$name.exr" "$ref" --diff "docs/images/${name}_flip.png")
  rel=$(echo "$out" | awk '/^relative MSE/ { print $3 }')
  flip=$(echo "$out" | awk '/^FLIP mean/ { print $3 }')
  ratio=$(echo "$out" | awk '/^mean ratio/ { print $3 }')
  echo "$name,$scene,$size,$refname,\"$config\",$rel,$flip,$ratio" >> "$csv"
  echo "$name: relative MSE $rel, FLIP $flip, mean ratio $ratio" >&2
done
cp "$csv" docs/results/lavapipe/figures.csv
