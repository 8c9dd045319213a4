#!/usr/bin/env bash
# Seventh run (54f851a): CPU rays against compute rays in one run, alternating, at HEAD; the
# 1 M-vertex compute bake; validation of the PRT bake, the reference and three method families.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
export PENUMBRA_CACHE=/tmp/pcache
exec > >(tee -a "$OUT/log14.txt") 2>&1
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
for case in "prt_bunny_cow 1024" "prt_throughput 1024"; do
  set -- $case; sc=$1; n=$2
  variant scenes/$sc.toml scenes/_g_cpu.toml "{ name = \"prt\", baker = \"rays_cpu\", samples = $n }"
  variant scenes/$sc.toml scenes/_g_gpu.toml "{ name = \"prt\", baker = \"rays\", samples = $n }"
  bake $bin bake scenes/_g_gpu.toml --method prt >/dev/null
  for rep in 1 2 3; do
    echo "== $sc $n cpu rays rep $rep"; bake $bin bake scenes/_g_cpu.toml --method prt
    echo "== $sc $n gpu rays rep $rep"; bake $bin bake scenes/_g_gpu.toml --method prt
  done
  echo "== $sc validation"; rm -rf /tmp/pcache; timeout 90 $bin bake scenes/_g_gpu.toml --method prt --validation >/tmp/v.log 2>&1; echo "exit $?"
done
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
for rep in 1 2 3; do echo "== million rep $rep"; bake $bin bake scenes/_g_million.toml --method prt; done
rm -f scenes/_g_*.toml
for case in "scenes/default.toml" "scenes/theatre_50.toml clustered" "scenes/sh_courtyard.toml sh_lightmap" "scenes/two_rooms.toml radiosity"; do
  set -- $case
  timeout 90 $bin capture "$1" ${2:+--method "$2"} --size 320x180 --frames 3 --validation -o /tmp/v.png >/tmp/v.log 2>&1
  echo "== validation: $*: exit $?"
done
timeout 60 $bin reference scenes/terrain_mountains.toml --size 64x64 --spp 16 --validation -o /tmp/v.exr >/tmp/v.log 2>&1; echo "== validation: reference terrain: exit $?"
echo "== done"
