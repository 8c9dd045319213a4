#!/usr/bin/env bash
# Eighth run: the GPU PRT bake's inputs mapped on every core (new) against 54f851a (old), on the
# 1 M-vertex scene and prt_throughput, alternating.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
export PENUMBRA_CACHE=/tmp/pcache
exec > >(tee -a "$OUT/log15.txt") 2>&1
variant() { python3 - "$1" "$2" "$3" <<'PY'
import re, sys
src, dst, methods = sys.argv[1:]
text = open(src).read()
text = re.sub(r"(?ms)^methods = \[\s*\n.*?^\]\n|^methods = \[[^\n]*\]\n", "", text, count=1)
open(dst, "w").write("methods = [ %s ]\n" % methods + text)
PY
}
bake() { rm -rf /tmp/pcache; timeout 60 "$@" 2>&1 | grep -E "prt rays"; }
variant scenes/prt_throughput.toml scenes/_g_gpu.toml '{ name = "prt", baker = "rays", samples = 1024 }'
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
bake .gl/bin/penumbra_new bake scenes/_g_gpu.toml --method prt >/dev/null
bake .gl/bin/penumbra_old bake scenes/_g_gpu.toml --method prt >/dev/null
for rep in 1 2 3; do
  for b in old new; do
    echo "== million $b rep $rep"; bake .gl/bin/penumbra_$b bake scenes/_g_million.toml --method prt
    echo "== prt_throughput $b rep $rep"; bake .gl/bin/penumbra_$b bake scenes/_g_gpu.toml --method prt
  done
done
rm -f scenes/_g_*.toml
echo "== done"
