#!/usr/bin/env bash
# Third lease, sixth run: the walk test on NVIDIA after the octant links are uploaded only when
# the ordered walk is first used (the renderer starts with the stack walk, a GPU's default).
set -u
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
exec > >(tee -a "$OUT/log21.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
PENUMBRA_TEST_DEVICE=H200 timeout 200 .gl/bin/reference_test both_bvh_walks specialised_tracer furnace_converges --test-threads 1 2>&1 | tail -10
echo "== done"
