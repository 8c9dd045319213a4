#!/usr/bin/env bash
# Fifth run: the BVH build with a thread budget (new) against three fixed levels (old = cba654d),
# through the PRT compute bake's "trees" phase: prt_throughput (226k triangles) and 1,004,004
# vertices over four planes (2 M triangles), alternating.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
export PENUMBRA_CACHE=/tmp/pcache
exec > >(tee -a "$OUT/log10.txt") 2>&1
nproc; cat /sys/fs/cgroup/cpu.max 2>/dev/null
python3 - scenes/prt_throughput.toml scenes/_g_gpu.toml '{ name = "prt", baker = "rays", samples = 1024 }' <<'PY'
import re, sys
src, dst, methods = sys.argv[1:]
text = open(src).read()
text = re.sub(r"(?ms)^methods = \[\s*\n.*?^\]\n|^methods = \[[^\n]*\]\n", "", text, count=1)
open(dst, "w").write("methods = [ %s ]\n" % methods + text)
PY
cat >scenes/_g_million.toml <<'EOT'
methods = [ { name = "prt", baker = "rays", samples = 64 } ]
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
bake() { rm -rf /tmp/pcache; timeout 60 "$@" 2>&1 | grep -E "prt "; }
bake .gl/bin/penumbra_new bake scenes/_g_gpu.toml --method prt >/dev/null
for rep in 1 2 3; do
  for b in old new; do
    echo "== prt_throughput $b rep $rep"; bake .gl/bin/penumbra_$b bake scenes/_g_gpu.toml --method prt
    echo "== million $b rep $rep"; bake .gl/bin/penumbra_$b bake scenes/_g_million.toml --method prt
  done
done
rm -f scenes/_g_*.toml
echo "== done"
