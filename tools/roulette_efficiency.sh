#!/usr/bin/env bash
# How Russian roulette's first bounce trades speed for noise: for each scene and each
# `--roulette-after` value, `penumbra reference` renders at SIZE and SPP with two seeds, and the
# median of its printed efficiency (samples/s over the relative variance of one sample, the
# speed at which it reaches a given relative MSE) is tabled, with each row's best in bold.
# Independent samples (`--sampler independent`), as the README's table was measured; the
# binary must know that option (builds from 2026-12-04 night on). Run it on an idle machine.
#   tools/roulette_efficiency.sh [-b BINARY] [-s WxH] [-n SPP] [-k "1 2 3 5 8 off"] SCENE...
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/release/penumbra size=64x64 spp=64 ks="1 2 3 5 8 off"
while getopts b:s:n:k: opt; do
  case $opt in
    b) bin=$OPTARG ;;
    s) size=$OPTARG ;;
    n) spp=$OPTARG ;;
    k) ks=$OPTARG ;;
    *) exit 2 ;;
  esac
done
shift $((OPTIND - 1))
if [ $# -eq 0 ]; then
  echo "usage: tools/roulette_efficiency.sh [-b BINARY] [-s WxH] [-n SPP] [-k \"1 2 3 5 8 off\"] SCENE..." >&2
  exit 2
fi
[ -x "$bin" ] || { echo "roulette_efficiency.sh: $bin is not an executable file (cargo build --release)" >&2; exit 2; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
header="| scene |"
rule="|---|"
for k in $ks; do header+=" K = $k |"; rule+="---|"; done
echo "efficiency (samples/s over the relative variance of a sample; median of seeds 1 and 2), $size, $spp spp, $(date -u +%F)"
echo "$header"
echo "$rule"
for scene in "$@"; do
  effs=()
  for k in $ks; do
    vals=()
    for seed in 1 2; do
      log=$("$bin" reference "$scene" --size "$size" --spp "$spp" --seed "$seed" --roulette-after "$k" --sampler independent -o "$out/r.exr" 2>&1) || {
        echo "roulette_efficiency.sh: $scene, K = $k: $(tail -n 1 <<< "$log")" >&2; exit 1; }
      vals+=("$(sed -n 's/.*efficiency (samples\/s over it): \([0-9.e+-]*\).*/\1/p' <<< "$log")")
    done
    effs+=("${vals[*]}")
  done
  # The median of two is their mean; the row's best is marked.
  printf '%s\n' "${effs[@]}" | awk -v name="$(basename "$scene" .toml)" '
    { v[NR] = ($1 + $2) / 2; if (v[NR] > best) best = v[NR] }
    END { row = "| " name " |"; for (i = 1; i <= NR; i++) { s = sprintf("%.3g", v[i]); row = row " " (v[i] == best ? "**" s "**" : s) " |" } print row }'
done
