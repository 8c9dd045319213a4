#!/usr/bin/env bash
# Every method at its defaults on the Sponza-sized stand-in of tools/atrium.py: per scene and
# method, whether it ran or was refused (and the line that says why), the capture's wall time
# (bakes included, nothing cached) and peak resident memory, and the median frame of
# `penumbra profile` at 640x360. Writes CSV to standard output.
#
#   bash tools/atrium_defaults.sh [DIR] > docs/results/lavapipe/atrium_defaults.csv
#
# A capture is stopped after 15 minutes and a profile after 10 (status "timeout").
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-$(mktemp -d)}
bin=${PENUMBRA_BIN:-target/debug/penumbra}
[ -x "$bin" ] || cargo build --quiet
python3 tools/atrium.py "$dir" > /dev/null
export PENUMBRA_CACHE="$dir/cache"
info() { "$bin" info 2>/dev/null | awk -v k="$1" '$1 == k {$1 = ""; print substr($0, 2); exit}'; }
cpu=$(awk -F': ' '/^model name/ {print $2; exit}' /proc/cpuinfo)
echo "# device: $(info device) on a $(nproc)-core $cpu"
echo "# driver: $(info driver)"
echo "# commit: $(git rev-parse --short HEAD)$(git diff --quiet HEAD || echo '+changes') (dev profile)"
echo "# date: $(date +%F)"
echo "# command: bash tools/atrium_defaults.sh"
echo "scene,method,status,capture_s,peak_rss_mb,frame_ms,note"
run() {
  local scene=$1 method=$2 toml="$dir/${1}_$2.toml" log="$dir/${1}_$2.log"
  sed "s/^methods = .*/methods = [\"$method\"]/" "$dir/$scene.toml" > "$toml"
  local start=$SECONDS status=ok frame="" rc=0
  /usr/bin/time -f "rss_kb %M" timeout 900 "$bin" capture "$toml" --size 640x360 -o "$dir/${1}_$2.png" > "$log" 2>&1 || rc=$?
  local took=$((SECONDS - start))
  local rss_mb=$(( $(awk '/^rss_kb/ {print $2}' "$log") / 1024 ))
  local note
  note=$({ grep -E "^(error|$method:)" "$log" || true; } | head -2 | tr '\n' ' ' | tr ',' ';' | tr '"' "'")
  if [ "$rc" = 124 ]; then
    status=timeout
  elif [ "$rc" != 0 ]; then
    status=refused
  elif timeout 600 "$bin" profile "$toml" --size 640x360 --frames 3 > "$dir/${1}_$2.prof" 2>&1; then
    frame=$(awk '$1 == "frame" {print $2}' "$dir/${1}_$2.prof")
  else
    status=frame_timeout
  fi
  echo "$scene,$method,$status,$took,$rss_mb,$frame,$note"
}
for m in forward clustered shadow_volumes lpv radiosity sh_lightmap prt heightfield_pyramid; do run sun "$m"; done
for m in forward clustered shadow_volumes vls bsp_lights lpv radiosity; do run lamps "$m"; done
