#!/usr/bin/env bash
# Thread scaling of raycast's octree and of the obvhs BVH2 backend: 2048x2048 primary rays,
# depth only, for 1, 2, 4, 8 and 16 threads, three runs each; trace and build times come from
# the sidecar. Meant for a machine with many cores (reports/thread_scaling.md was made on a
# 16-core machine); BIG_SCENE adds a scene such as the 1M-triangle one tools/raycast_tools/bench.py writes.
#
# PINNING=1 adds a pinning experiment on the bunny and the helmet: one thread on CPU 0, two
# threads on CPU 0 and its hyperthread sibling (CPU 0 alone when it has none), two threads on
# CPU 0 and a CPU of another core (taskset, three runs each).
#
#   tools/thread_scaling.sh   -> reports/device/{machine,scaling,topology}.txt (+ pinning.txt)
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
{ lscpu; for c in /sys/devices/system/cpu/cpu[0-9]*; do
    echo "$(basename "$c") core $(cat "$c/topology/core_id") siblings $(cat "$c/topology/thread_siblings_list")"
  done; } > "$out/topology.txt" 2>&1 || true
[ "${PINNING:-0}" = 1 ] || exit 0
cpu=/sys/devices/system/cpu
sibling=$(tr ',-' '\n\n' < $cpu/cpu0/topology/thread_siblings_list | { grep -vx 0 || true; } | head -1)
sibling=${sibling:-0}
core0=$(cat $cpu/cpu0/topology/core_id)
other=$(for c in $cpu/cpu[0-9]*; do
  if [ "$(cat "$c/topology/core_id")" != "$core0" ]; then basename "$c" | tr -d cpu; fi
done | sort -n | head -1)
echo "sibling of cpu0: $sibling, another core: $other" > "$out/pinning.txt"
for scene in fixtures/assets/stanford-bunny.obj fixtures/assets/DamagedHelmet.glb; do
  for pin in 0 "0,$sibling" "0,$other"; do
    threads=$(tr ',' '\n' <<< "$pin" | sort -u | wc -l)
    for accel in octree bvh; do
      for run in 1 2 3; do
        taskset -c "$pin" "$raycast" "$scene" --width 2048 --height 2048 --aov depth --format npy \
          --threads "$threads" --accel "$accel" --out "$work" --quiet
        python3 -c "import json; t = json.load(open('$work/raycast.json'))['timings']; \
print('$(basename "$scene")', 'cpus=$pin', '$accel', $threads, $run, t['trace'])" >> "$out/pinning.txt"
      done
    done
  done
done
