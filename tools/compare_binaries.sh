#!/usr/bin/env bash
# Renders every scene file under fixtures/ and ../shared/assets (under 8 MB) with two raycast
# binaries and compares their npy buffers (depth, normal, id, prim at 48x40) byte for byte:
# what "static scenes: outputs byte-identical" is checked with (reports/posing_static_cost.md).
# With --messages it also compares, per file, what the user reads: the render's messages and
# sidecar, `raycast info` and `raycast check -v` (stdout, stderr, exit status), with timings
# masked (durations such as "0.013s" and the sidecar's "timings"): what a change that must
# not change behaviour (issue 30's restructuring) is checked with.
#
#   tools/compare_binaries.sh [--messages] OLD_RAYCAST NEW_RAYCAST
# Prints each file whose buffers, exit status or messages differ, then the counts.
set -uo pipefail
messages=0
[ "${1:-}" = --messages ] && { messages=1; shift; }
[ $# -eq 2 ] || { echo "usage: tools/compare_binaries.sh [--messages] OLD_RAYCAST NEW_RAYCAST" >&2; exit 2; }
old=$1 new=$2
cd "$(dirname "$0")/.."
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
same=0 differ=0 both_fail=0 status=0 total=0
# Both binaries write to the same folder, one after the other, so that messages naming it match.
render() {
  rm -rf "$work/out"
  timeout 60 "$1" "$2" --width 48 --height 40 --aov depth,normal,id,prim --format npy \
    --out "$work/out" >"$work/out.log" 2>&1
  local rc=$?
  mv "$work/out.log" "$3.log"; [ -d "$work/out" ] && mv "$work/out" "$3"
  return $rc
}
# What a user reads of BINARY on FILE, timings masked, into OUT.
said() {
  local bin=$1 f=$2 out=$3
  {
    if [ -f "$work/$(basename "$out" .said)/raycast.json" ]; then
      jq -S 'del(.timings)' "$work/$(basename "$out" .said)/raycast.json"
    fi
    cat "$work/$(basename "$out" .said).log"
    echo "== info"; timeout 60 "$bin" info "$f" 2>&1; echo "exit $?"
    echo "== check"; timeout 60 "$bin" check -v "$f" 2>&1; echo "exit $?"
  } | sed -E 's/[0-9]+(\.[0-9]+)?s\b/<time>s/g' >"$out"
}
mismatch=0
while read -r f; do
  total=$((total + 1))
  render "$old" "$f" "$work/old"; a=$?
  render "$new" "$f" "$work/new"; b=$?
  if [ $a -ne 0 ] && [ $b -ne 0 ]; then
    both_fail=$((both_fail + 1))
  elif [ $a -ne $b ]; then
    status=$((status + 1)); echo "exit $a -> $b: $f"
  else
    ok=1
    for x in depth normal id prim; do cmp -s "$work/old/$x.npy" "$work/new/$x.npy" || ok=0; done
    if [ $ok = 1 ]; then same=$((same + 1)); else differ=$((differ + 1)); echo "buffers differ: $f"; fi
  fi
  if [ $messages = 1 ]; then
    said "$old" "$f" "$work/old.said"; said "$new" "$f" "$work/new.said"
    if ! cmp -s "$work/old.said" "$work/new.said"; then
      mismatch=$((mismatch + 1)); echo "messages differ: $f"
      diff "$work/old.said" "$work/new.said" | head -6
    fi
  fi
  rm -rf "$work/old" "$work/new" "$work"/*.log "$work"/*.said
done < <(find fixtures ../shared/assets -type f \( -name '*.gltf' -o -name '*.glb' -o -name '*.obj' \
  -o -name '*.usda' -o -name '*.usd' -o -name '*.usdc' -o -name '*.usdz' -o -name '*.ply' -o -name '*.stl' \) \
  -size -8M 2>/dev/null | sort)
echo "$total files: $same identical, $differ differ, $status changed exit status, $both_fail refused by both"
if [ $messages = 1 ]; then echo "messages, sidecars, info and check: $mismatch files differ"; fi
