#!/usr/bin/env bash
# The demo left running: `penumbra demo` under Xvfb on one scene, switching to the
# next method or combination every CYCLE frames, for MINUTES minutes, with the process's resident
# memory (VmRSS, and RssAnon: on lavapipe the device's memory is the process's) sampled every 30 s.
#   tools/demo_soak.sh [SCENE] [MINUTES] [OUT.csv]
#   PENUMBRA_DEMO_CYCLE (default 500), PENUMBRA_DEMO_SIZE (default 320x180)
# Writes CSV: seconds,vm_rss_mib,rss_anon_mib (the demo's output beside it, OUT.log); the demo
# runs under validation, and how it ended is the last line.
set -euo pipefail
cd "$(dirname "$0")/.."
scene="${1:-scenes/bsp_rooms.toml}"
minutes="${2:-60}"
out="${3:-demo_soak.csv}"
bash tools/setup.sh >/dev/null
cargo build --quiet
export PENUMBRA_TEST_DEVICE="${PENUMBRA_TEST_DEVICE:-llvmpipe}"
xvfb-run -a -s "-screen 0 1024x768x24" ./target/debug/penumbra demo "$scene" --validation --device llvmpipe \
    --size "${PENUMBRA_DEMO_SIZE:-320x180}" --cycle-every "${PENUMBRA_DEMO_CYCLE:-500}" >"${out%.csv}.log" 2>&1 &
runner=$!
# The demo process itself (a child of xvfb-run).
pid=""
for _ in $(seq 1 60); do
    pid=$(pgrep -n -x penumbra || true)
    [ -n "$pid" ] && break
    sleep 1
done
[ -n "$pid" ] || { echo "the demo did not start: see ${out%.csv}.log" >&2; exit 1; }
echo "seconds,vm_rss_mib,rss_anon_mib" >"$out"
start=$(date +%s)
while kill -0 "$pid" 2>/dev/null; do
    now=$(($(date +%s) - start))
    awk -v t="$now" '/^VmRSS/ {v=$2} /^RssAnon/ {a=$2} END {printf "%d,%.1f,%.1f\n", t, v/1024, a/1024}' "/proc/$pid/status" >>"$out" 2>/dev/null || true
    [ "$now" -ge $((minutes * 60)) ] && break
    sleep 30
done
if kill -0 "$pid" 2>/dev/null; then
    kill "$pid"
    wait "$runner" 2>/dev/null || true
    echo "# ran $minutes minutes; stopped by the script" >>"$out"
else
    wait "$runner" && status=0 || status=$?
    echo "# the demo exited by itself with status $status (see ${out%.csv}.log)" >>"$out"
fi
