#!/usr/bin/env bash
# Thread scaling of raycast's octree and of the obvhs BVH2 backend: 2048x2048 primary rays,
# depth only, for 1, 2, 4, 8 and 16 threads, three runs each; trace and build times come from
# the sidecar. Meant for a machine with many cores (reports/thread_scaling.md was made on a
# 16-core machine); BIG_SCENE adds a scene such as the 1M-triangle one tools/bench.py writes.
#
#   tools/thread_scaling.sh            -> reports/device/machine.txt, reports/device/scaling.txt
set -euo pipefail
cd "$(dirname "$0")/.."
raycast=${RAYCAST:-target/release/raycast}
out=${OUT:-reports/device}
mkdir -p "$out"
echo "cpu: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2)" > "$out/machine.txt"
: > "$out/scaling.txt"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for scene in fixtures/assets/stanford-bunny.obj fixtures/assets/DamagedHelmet.glb ${BIG_SCENE:-}; do
  for accel in octree bvh; do
    for threads in 1 2 4 8 16; do
      for run in 1 2 3; do
        "$raycast" "$scene" --width 2048 --height 2048 --aov depth --format npy \
          --threads "$threads" --accel "$accel" --out "$work" --quiet
        python3 -c "import json; t = json.load(open('$work/raycast.json'))['timings']; \
print('$(basename "$scene")', '$accel', $threads, $run, t['build'], t['trace'])" >> "$out/scaling.txt"
      done
    done
  done
done
