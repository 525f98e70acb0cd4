#!/usr/bin/env bash
# Where the trace instructions go (valgrind's callgrind; deterministic, unlike wall time on a
# shared machine): for each scene, instructions per ray of the whole trace, of
# the primitive tests, and of the octree's traversal (per-ray set-up excluded); then the
# octree's per-ray counts (benches/octree_counts.rs). Coherent 512x512 camera rays, depth only, one thread.
# reports/octree_profile.md quotes its output.
#
#   tools/profile_trace.sh [SCENE...]    (default: the bunny and the helmet in fixtures/assets)
set -euo pipefail
cd "$(dirname "$0")/.."
command -v valgrind >/dev/null || { echo "profile_trace.sh: valgrind is not installed" >&2; exit 2; }
cargo build --release --quiet
raycast=target/release/raycast
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(fixtures/assets/stanford-bunny.obj fixtures/assets/DamagedHelmet.glb)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
rays=$((512 * 512))
for scene in "${scenes[@]}"; do
  for accel in octree; do
    valgrind --tool=callgrind --toggle-collect='*Tracer as raycast_core::trace::NearestHits>::nearest_all' \
      --callgrind-out-file="$work/cg.out" "$raycast" "$scene" --width 512 --height 512 \
      --threads 1 --quiet --format npy --aov depth --out "$work/out" >/dev/null 2>&1
    callgrind_annotate --inclusive=yes "$work/cg.out" > "$work/cg.txt" 2>/dev/null
    total=$(grep 'PROGRAM TOTALS' "$work/cg.txt" | awk '{gsub(",", "", $1); print $1}')
    # Inclusive counts of the first (outermost) entry of each function.
    count() { grep -m1 "$1" "$work/cg.txt" | awk '{gsub(",", "", $1); print $1}'; }
    tests=$(count 'triangle::WatertightRay::intersect$\|triangle::WatertightRay::intersect \[')
    # Single-ray and packet traversal (AVX2 kernels; the packets' single-ray tail is inlined).
    single=$(count 'octree::traverse::run_avx2 \[' || true)
    packets=$(count 'octree::packet::run_avx2 \[' || true)
    cells=$(( ${single:-0} + ${packets:-0} ))
    awk -v s="$(basename "$scene")" -v a="$accel" -v t="$total" -v p="${tests:-0}" -v c="${cells:-0}" -v n=$rays 'BEGIN {
      printf "%s %s: %.0f instructions/ray; triangle tests %.0f (%.1f%%)", s, a, t/n, p/n, 100*p/t
      if (c > 0) printf "; octree cells excluding tests %.0f (%.1f%%)", (c-p)/n, 100*(c-p)/t
      printf "\n" }'
  done
  cargo bench --quiet --bench octree_counts -- "$scene" 512
done
