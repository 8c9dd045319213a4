#!/usr/bin/env bash
# Device session 2026-12-04 afternoon, second run: PRT ray bake with the lanes reduced on the
# GPU (new) against a2114aa (old), bunny_cow at 256/1024/4096 rays and prt_throughput at 1024;
# PRT run-time shading spread on 1,004,004 vertices.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
export PENUMBRA_CACHE=/tmp/pcache
exec > >(tee -a "$OUT/log2.txt") 2>&1
variant() { python3 - "$1" "$2" "$3" <<'PY'
import re, sys
src, dst, methods = sys.argv[1:]
text = open(src).read()
text = re.sub(r"(?ms)^methods = \[\s*\n.*?^\]\n|^methods = \[[^\n]*\]\n", "", text, count=1)
open(dst, "w").write("methods = [ %s ]\n" % methods + text)
PY
}
bake() { rm -rf /tmp/pcache; timeout 60 "$@" 2>&1 | grep -E "prt "; }
for case in "prt_bunny_cow 256" "prt_bunny_cow 1024" "prt_bunny_cow 4096" "prt_throughput 1024"; do
  set -- $case; sc=$1; n=$2
  variant scenes/$sc.toml scenes/_g_cpu.toml "{ name = \"prt\", baker = \"rays_cpu\", samples = $n }"
  variant scenes/$sc.toml scenes/_g_gpu.toml "{ name = \"prt\", baker = \"rays\", samples = $n }"
  for rep in 1 2 3; do
    echo "== $sc $n cpu rays rep $rep"; bake .gl/bin/penumbra_new bake scenes/_g_cpu.toml --method prt
    for b in old new; do echo "== $sc $n gpu rays $b rep $rep"; bake .gl/bin/penumbra_$b bake scenes/_g_gpu.toml --method prt; done
  done
  if [ "$n" = 1024 ]; then
    rm -rf /tmp/c_old /tmp/c_new
    PENUMBRA_CACHE=/tmp/c_old timeout 60 .gl/bin/penumbra_old bake scenes/_g_gpu.toml --method prt >/dev/null 2>&1
    PENUMBRA_CACHE=/tmp/c_new timeout 60 .gl/bin/penumbra_new bake scenes/_g_gpu.toml --method prt >/dev/null 2>&1
    python3 - /tmp/c_old/bake/*.bin /tmp/c_new/bake/*.bin <<'PY'
import struct, sys
a, b = (open(f, "rb").read() for f in sys.argv[1:3])
n = (len(a) - 32) // 4
fa = struct.unpack("<%df" % n, a[32:32 + 4 * n]); fb = struct.unpack("<%df" % n, b[32:32 + 4 * n])
print("old vs new transfer: %d values, max |diff| %.3g, max |value| %.3g" % (n, max(abs(x - y) for x, y in zip(fa, fb)), max(abs(x) for x in fa)))
PY
  fi
done
rm -f scenes/_g_*.toml
cat >scenes/_g_million.toml <<'EOT'
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
EOT
for x in -4.5 -1.5 1.5 4.5; do
  printf '[[objects]]\nname = "plane%s"\nmesh = "plane"\nsize = 3\nsubdivisions = 500\nmaterial = "floor"\ntranslate = [%s, 0, 0]\n' "$x" "$x" >>scenes/_g_million.toml
done
echo "== PRT shading, 1,004,004 vertices, 300 frames"
timeout 90 .gl/bin/penumbra_new profile scenes/_g_million.toml --method prt --size 1280x720 --frames 300 2>&1 | tail -12
echo "== forward, same mesh, 300 frames"
timeout 60 .gl/bin/penumbra_new profile scenes/_g_million.toml --method forward --size 1280x720 --frames 300 2>&1 | tail -8
rm -f scenes/_g_million.toml
echo "== done"
