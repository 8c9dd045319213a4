#!/usr/bin/env bash
# Third lease, fourth run: the BVH build with the first subtree of a threaded split built in
# place (new) against both subtrees copied in (old), `measure_build_time_against_threads`,
# alternating, twice each.
set -u
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
exec > >(tee -a "$OUT/log19.txt") 2>&1
nproc
for r in 1 2; do
  for v in old new; do
    echo "== round $r $v"
    timeout 120 .gl/bin/lib_$v measure_build_time --ignored --nocapture 2>&1 | grep -E "triangles|threads"
  done
done
echo "== done"
