#!/usr/bin/env bash
# Third lease, second run: the walk chosen per device (the stack walk on a GPU), and the test
# that the two walks give the same image, on NVIDIA's driver.
set -u
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
exec > >(tee -a "$OUT/log17.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
for r in 1 2 3; do
  echo -n "round $r cornell32: "
  timeout 60 .gl/bin/penumbra_new reference scenes/cornell.toml --size 1024x1024 --seed 1 --bounces 32 --spp 64 -o /tmp/ref.exr 2>&1 | grep -E "samples/s|rror" | head -1
  echo -n "round $r furnace: "
  timeout 60 .gl/bin/penumbra_new reference scenes/furnace.toml --size 1024x1024 --seed 1 --spp 16 -o /tmp/ref.exr 2>&1 | grep -E "samples/s|rror" | head -1
done
echo "== tests on the H200"
PENUMBRA_TEST_DEVICE=H200 timeout 200 .gl/bin/reference_test both_bvh_walks specialised_tracer russian_roulette furnace_converges quad_light_over --test-threads 1 2>&1 | tail -25
echo "== done"
