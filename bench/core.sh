#!/usr/bin/env bash
# The core benchmarks recorded in BENCHMARKS.md: BVH build and traversal,
# and full Cornell-box renders. Run from the repository root on an idle machine.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --profile dist --features x86-64-v3 --quiet
bin=target/dist/lenspath
dragon=../shared/meshes/dragon_100k.ply

for threads in 1 2; do
  "$bin" bench bvh --procedural 1000000 --threads "$threads" --json
  if [ -f "$dragon" ]; then
    "$bin" bench bvh "$dragon" --threads "$threads" --json
  else
    echo "skipping the dragon: $dragon not found" >&2
  fi
done

out=$(mktemp -d)
for run in 1 2 3; do
  "$bin" render --camera pinhole --res 480x360 --spp 4 --light-samples 4 --max-depth 16 --out "$out/a.png" 2>&1 | tail -n 1
  "$bin" render --camera pinhole --res 480x360 --spp 16 --light-samples 16 --max-depth 16 --out "$out/b.png" 2>&1 | tail -n 1
done
# The realistic camera (dgauss50, the default) against the pinhole at equal spp,
# interleaved; whole-process wall time, so the camera's set-up counts.
for run in 1 2 3 4 5; do
  for camera in realistic pinhole; do
    start=$EPOCHREALTIME
    "$bin" render --camera "$camera" --res 480x360 --spp 4 --light-samples 4 --max-depth 16 --out "$out/c.png" 2>/dev/null
    end=$EPOCHREALTIME
    awk -v c="$camera" -v s="$start" -v e="$end" 'BEGIN { printf "%s %.3f s\n", c, e - s }'
  done
done
rm -rf "$out"
