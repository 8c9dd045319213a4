#!/usr/bin/env bash
# Fourth run (cba654d): CPU rays against compute rays in one run, alternating; every method
# family under the validation layer with the new memory blocks; the prt_bunny_cow chart.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
export PENUMBRA_CACHE=/tmp/pcache
exec > >(tee -a "$OUT/log9.txt") 2>&1
bin=.gl/bin/penumbra
variant() { python3 - "$1" "$2" "$3" <<'PY'
import re, sys
src, dst, methods = sys.argv[1:]
text = open(src).read()
text = re.sub(r"(?ms)^methods = \[\s*\n.*?^\]\n|^methods = \[[^\n]*\]\n", "", text, count=1)
open(dst, "w").write("methods = [ %s ]\n" % methods + text)
PY
}
bake() { rm -rf /tmp/pcache; timeout 60 "$@" 2>&1 | grep -E "prt "; }
for case in "prt_bunny_cow 1024" "prt_bunny_cow 4096" "prt_throughput 1024"; do
  set -- $case; sc=$1; n=$2
  variant scenes/$sc.toml scenes/_g_cpu.toml "{ name = \"prt\", baker = \"rays_cpu\", samples = $n }"
  variant scenes/$sc.toml scenes/_g_gpu.toml "{ name = \"prt\", baker = \"rays\", samples = $n }"
  bake $bin bake scenes/_g_gpu.toml --method prt >/dev/null # the driver's pipeline cache
  for rep in 1 2 3; do
    echo "== $sc $n cpu rays rep $rep"; bake $bin bake scenes/_g_cpu.toml --method prt
    echo "== $sc $n gpu rays rep $rep"; bake $bin bake scenes/_g_gpu.toml --method prt
  done
done
rm -f scenes/_g_*.toml
for case in "scenes/default.toml" "scenes/bsp_rooms.toml seed000" "scenes/lpv_bush.toml lpv_over_forward" \
    "scenes/theatre_50.toml bsp_lights" "scenes/theatre_50.toml vls" "scenes/theatre_50.toml clustered" \
    "scenes/theatre_50.toml shadow_volumes" "scenes/prt_teapot_box.toml prt" "scenes/sh_courtyard.toml sh_lightmap" \
    "scenes/terrain_sky.toml heightfield_pyramid" "scenes/terrain_sky.toml heightfield_bruteforce" "scenes/two_rooms.toml radiosity"; do
  set -- $case
  timeout 90 $bin capture "$1" ${2:+--method "$2"} --size 320x180 --frames 3 --validation -o /tmp/v.png >/tmp/v.log 2>&1
  echo "== validation: $*: exit $?"; grep -iE "VUID|error" /tmp/v.log | head -3
done
timeout 60 $bin reference scenes/cornell.toml --size 64x64 --spp 16 --validation -o /tmp/v.exr >/tmp/v.log 2>&1; echo "== validation: reference: exit $?"
t0=$SECONDS
timeout 200 $bin chart scenes/prt_bunny_cow.toml --size 640x360 --cache-dir /tmp/pcache -o $OUT/chart_prt_bunny_cow.png --csv $OUT/chart_prt_bunny_cow.csv 2>&1 | tail -25
echo "== chart prt_bunny_cow 640x360: $((SECONDS - t0)) s"
echo "== done"
