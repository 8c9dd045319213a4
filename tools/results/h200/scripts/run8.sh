#!/usr/bin/env bash
# Third run: where the PRT compute bake's set-up goes on NVIDIA (a = gpu-allocator's default
# blocks, 256 MiB device / 64 MiB host; b = blocks growing from 8 MiB), validation of the bake
# with the GPU reduction, and the default scene's capture wall time with a and b.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
export PENUMBRA_CACHE=/tmp/pcache
exec > >(tee -a "$OUT/log3.txt") 2>&1
variant() { python3 - "$1" "$2" "$3" <<'PY'
import re, sys
src, dst, methods = sys.argv[1:]
text = open(src).read()
text = re.sub(r"(?ms)^methods = \[\s*\n.*?^\]\n|^methods = \[[^\n]*\]\n", "", text, count=1)
open(dst, "w").write("methods = [ %s ]\n" % methods + text)
PY
}
bake() { rm -rf /tmp/pcache; timeout 60 "$@" 2>&1 | grep -E "prt |rror|alidation"; }
for sc in prt_bunny_cow prt_throughput; do
  variant scenes/$sc.toml scenes/_g_gpu.toml '{ name = "prt", baker = "rays", samples = 1024 }'
  echo "== $sc validation"; rm -rf /tmp/pcache; timeout 90 .gl/bin/penumbra_a bake scenes/_g_gpu.toml --method prt --validation >/tmp/v.log 2>&1; echo "exit $?"; grep -E "prt |rror|VUID|alid" /tmp/v.log | head
  for rep in 1 2 3; do
    for b in a b; do echo "== $sc 1024 gpu rays $b rep $rep"; bake .gl/bin/penumbra_$b bake scenes/_g_gpu.toml --method prt; done
  done
done
rm -f scenes/_g_*.toml
for rep in 1 2 3; do
  for b in a b; do
    t0=$(date +%s%N); timeout 60 .gl/bin/penumbra_$b capture --size 1280x720 -o /tmp/cap.png >/dev/null 2>&1; rc=$?; t1=$(date +%s%N)
    echo "== capture default scene $b rep $rep: exit $rc, $(( (t1 - t0) / 1000000 )) ms"
  done
done
echo "== done"
