#!/usr/bin/env bash
# Reference speed, A against B: two penumbra binaries (e.g. release builds of two commits)
# render the cases of tools/reference_vs_mitsuba.py at 64x64, alternating, ROUNDS times
# (default 3), and the median samples/s of each is printed. Run it on an idle machine.
# Each binary renders with its own default sampler: builds before 2026-12-04 night use
# independent samples, later ones Sobol points (a few per cent slower per sample), so compare
# builds of the same side of that change, or read the rates with that in mind.
#   tools/reference_ab.sh OLD_BINARY NEW_BINARY [ROUNDS]
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 2 ]; then
  echo "usage: tools/reference_ab.sh OLD_BINARY NEW_BINARY [ROUNDS]" >&2
  exit 2
fi
a=$1 b=$2 rounds=${3:-3}
for bin in "$a" "$b"; do
  [ -x "$bin" ] || { echo "reference_ab.sh: $bin is not an executable file" >&2; exit 2; }
done
cases=("cornell32|scenes/cornell.toml|--bounces 32 --spp 64"
       "direct|scenes/cornell.toml|--direct-only --spp 256"
       "furnace|scenes/furnace.toml|--spp 16"
       "terrain|scenes/terrain_mountains.toml|--spp 64")
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for ((r = 1; r <= rounds; r++)); do
  for c in "${cases[@]}"; do
    IFS='|' read -r name scene args <<< "$c"
    for side in a b; do
      bin=$a; [ "$side" = b ] && bin=$b
      # shellcheck disable=SC2086
      log=$("$bin" reference "$scene" --size 64x64 --seed 1 $args -o "$out/$side.exr" 2>&1) || true
      rate=$(grep -o '[0-9]* samples/s' <<< "$log" | cut -d' ' -f1 || true)
      if [ -z "$rate" ]; then
        echo "reference_ab.sh: $bin gave no rate for $name: $(tail -n 1 <<< "$log")" >&2
        exit 1
      fi
      echo "$name $side $rate" >> "$out/rates"
      echo "round $r: $name $side $rate samples/s"
    done
  done
done
echo "| case | A samples/s | B samples/s | B / A |"
echo "|---|---|---|---|"
for c in "${cases[@]}"; do
  name=${c%%|*}
  med() { grep "^$name $1 " "$out/rates" | cut -d' ' -f3 | sort -n | awk '{v[NR]=$1} END {print (NR % 2) ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2}'; }
  ma=$(med a); mb=$(med b)
  awk -v n="$name" -v a="$ma" -v b="$mb" 'BEGIN {printf "| %s | %.1f k | %.1f k | %.2f |\n", n, a/1e3, b/1e3, b/a}'
done
