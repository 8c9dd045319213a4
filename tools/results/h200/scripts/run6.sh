#!/usr/bin/env bash
# Device session 2026-12-04 afternoon: PRT ray-bake ramp (old = a2114aa, new = chunk growth x8),
# many-lights scaling after the clustered coarse pass, PRT run-time shading spread.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
export PENUMBRA_CACHE=/tmp/pcache
log=$OUT/log.txt
exec > >(tee -a "$log") 2>&1
old=.gl/bin/penumbra_old; new=.gl/bin/penumbra_new
$new info 2>&1 | head -20
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv
variant() { python3 - "$1" "$2" "$3" <<'PY'
import re, sys
src, dst, methods = sys.argv[1:]
text = open(src).read()
text = re.sub(r"(?ms)^methods = \[\s*\n.*?^\]\n|^methods = \[[^\n]*\]\n", "", text, count=1)
open(dst, "w").write("methods = [ %s ]\n" % methods + text)
PY
}
for sc in prt_bunny_cow prt_throughput; do
  variant scenes/$sc.toml scenes/_g_cpu.toml '{ name = "prt", baker = "rays_cpu", samples = 1024 }'
  variant scenes/$sc.toml scenes/_g_gpu.toml '{ name = "prt", baker = "rays", samples = 1024 }'
  echo "== $sc cpu rays"; rm -rf /tmp/pcache; timeout 60 $new bake scenes/_g_cpu.toml --method prt 2>&1 | grep -E "prt "
  for rep in 1 2 3; do
    for b in old new; do
      echo "== $sc gpu rays $b rep $rep"; rm -rf /tmp/pcache; bin=.gl/bin/penumbra_$b
      timeout 60 $bin bake scenes/_g_gpu.toml --method prt 2>&1 | grep -E "prt "
    done
  done
  echo "== $sc cpu rays again"; rm -rf /tmp/pcache; timeout 60 $new bake scenes/_g_cpu.toml --method prt 2>&1 | grep -E "prt "
done
rm -f scenes/_g_*.toml
echo "== many lights, fixed stage"; date -u +%T
timeout 150 python3 tools/many_lights_scaling.py --binary $new --counts 1,4,16,64,256,1024,2048,4096 --frames 10 --size 1280x720 --timeout 60 --out $OUT/ml_fixed 2>&1 | tail -15
echo "== many lights, constant coverage"; date -u +%T
timeout 150 python3 tools/many_lights_scaling.py --binary $new --coverage constant --counts 1,4,16,64,256,1024,2048,4096 --frames 10 --size 1280x720 --timeout 60 --out $OUT/ml_const 2>&1 | tail -15
echo "== done"; date -u +%T
