#!/usr/bin/env bash
# Third lease, fifth run: the BVH build with threads' subtrees grafted when the tree is
# flattened, every node copied once (new2), against the first subtree in place and the second
# copied in (new, 8defd87) and both copied in (old), `measure_build_time_against_threads`,
# alternating, two rounds.
set -u
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
exec > >(tee -a "$OUT/log20.txt") 2>&1
nproc
for r in 1 2; do
  for v in old new new2; do
    echo "== round $r $v"
    timeout 120 .gl/bin/lib_$v measure_build_time --ignored --nocapture 2>&1 | grep -E "triangles|threads"
  done
done
echo "== done"
