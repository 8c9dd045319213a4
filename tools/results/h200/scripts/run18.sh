#!/usr/bin/env bash
# Third lease, third run: the two tests that compare two compilations of the tracer, after they
# ask for bit identity on CPU devices only and for equal means within four standard errors on
# a GPU.
set -u
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
exec > >(tee -a "$OUT/log18.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
PENUMBRA_TEST_DEVICE=H200 timeout 200 .gl/bin/reference_test both_bvh_walks specialised_tracer --test-threads 1 2>&1 | tail -12
echo "== done"
