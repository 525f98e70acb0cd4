#!/usr/bin/env bash
# Renders every scene file under fixtures/ and ../shared/assets (under 8 MB) with two raycast
# binaries and compares their npy buffers (depth, normal, id, prim at 48x40) byte for byte:
# what "static scenes: outputs byte-identical" is checked with (reports/posing_static_cost.md).
#
#   tools/compare_binaries.sh OLD_RAYCAST NEW_RAYCAST
# Prints each file whose buffers or exit status differ, then the counts.
set -uo pipefail
[ $# -eq 2 ] || { echo "usage: tools/compare_binaries.sh OLD_RAYCAST NEW_RAYCAST" >&2; exit 2; }
old=$1 new=$2
cd "$(dirname "$0")/.."
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
same=0 differ=0 both_fail=0 status=0 total=0
render() { timeout 60 "$1" "$2" --width 48 --height 40 --aov depth,normal,id,prim --format npy --out "$3" -q >/dev/null 2>&1; }
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
  rm -rf "$work/old" "$work/new"
done < <(find fixtures ../shared/assets -type f \( -name '*.gltf' -o -name '*.glb' -o -name '*.obj' \
  -o -name '*.usda' -o -name '*.usd' -o -name '*.usdc' -o -name '*.usdz' -o -name '*.ply' -o -name '*.stl' \) \
  -size -8M 2>/dev/null | sort)
echo "$total files: $same identical, $differ differ, $status changed exit status, $both_fail refused by both"
