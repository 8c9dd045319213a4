#!/usr/bin/env bash
# `penumbra chart` on the Sponza-sized stand-in of tools/atrium.py: every method its scene
# declares, at every point of its sweep, against the path-traced reference. A swept point still
# baking after the bake limit is left out with why (the scene's own configurations always run).
# Writes the chart's CSV, with a header naming the device and command, to standard output.
#
#   bash tools/atrium_chart.sh [SCENE [SIZE [BAKE_LIMIT_S [DIR]]]] > docs/results/lavapipe/atrium_chart_sun.csv
#
# SCENE is sun (default) or lamps; SIZE 64x36; BAKE_LIMIT_S 120.
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-sun}
size=${2:-64x36}
limit=${3:-120}
dir=${4:-$(mktemp -d)}
bin=${PENUMBRA_BIN:-target/debug/penumbra}
[ -x "$bin" ] || cargo build --quiet
python3 tools/atrium.py "$dir" > /dev/null
info() { "$bin" info 2>/dev/null | awk -v k="$1" '$1 == k {$1 = ""; print substr($0, 2); exit}'; }
cpu=$(awk -F': ' '/^model name/ {print $2; exit}' /proc/cpuinfo)
# The header is taken before the chart runs: the commit is the one the binary was built from.
header="# device: $(info device) on a $(nproc)-core $cpu
# driver: $(info driver)
# commit: $(git rev-parse --short HEAD)$(git diff --quiet HEAD || echo '+changes') (dev profile)
# date: $(date +%F)
# command: bash tools/atrium_chart.sh $scene $size $limit"
start=$SECONDS
"$bin" chart "$dir/$scene.toml" --size "$size" --bake-limit "$limit" --cache-dir "$dir/cache" \
  -o "$dir/chart.png" --csv "$dir/chart.csv" > "$dir/chart.log" 2>&1 || { cat "$dir/chart.log" >&2; exit 1; }
echo "$header"
echo "# note: nothing cached at the start; the whole chart took $((SECONDS - start)) s; left out: $(grep -c 'left out' "$dir/chart.log" || true) swept point(s) ($(grep 'left out' "$dir/chart.log" | sed 's/^chart: //; s/ left out: .*//' | tr '\n' ';' | sed 's/;$//'))"
cat "$dir/chart.csv"
