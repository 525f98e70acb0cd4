#!/usr/bin/env bash
# Remakes fixtures/posed/ (issue 28): the public posed samples copied from the shared asset
# folder (../shared/assets/gltf/posed, or $RAYCAST_ASSETS/gltf/posed), hand-made morph and skin
# fixtures (tools/npm/make_pose_fixtures.mjs) with Draco and meshopt versions, and for every file
# the reference pose of three.js's GLTFLoader (tools/npm/pose_reference.mjs) in
# fixtures/posed/three/<file>.json. A Draco file's reference is three.js on its plain decode
# (`*.plain.glb`, glTF-Transform with the official draco3dgltf decoder): three.js's DRACOLoader
# needs web workers, which node does not have.
#
# Tools are pinned in tools/npm/package-lock.json (three, gltfpack, @gltf-transform/*); this script
# installs them with `npm ci` when missing. Every made file is checked with the Khronos
# glTF-Validator and must have no error.
set -euo pipefail

repo=$(cd "$(dirname "$0")/.." && pwd)
npm_dir="$repo/tools/npm"
assets=${RAYCAST_ASSETS:-$repo/../shared/assets}/gltf/posed
out="$repo/fixtures/posed"
[ -d "$assets" ] || { echo "make_pose_fixtures: no asset folder at $assets" >&2; exit 1; }
[ -d "$npm_dir/node_modules/three" ] || (cd "$npm_dir" && npm ci --no-audit --no-fund)

gltfpack="$npm_dir/node_modules/.bin/gltfpack"
transform="$npm_dir/node_modules/.bin/gltf-transform"
helper() { node "$npm_dir/gltf_helper.mjs" "$@"; }
mkdir -p "$out/three"
rm -f "$out"/*.glb "$out"/*.gltf "$out"/*.bin "$out"/three/*.json

cp "$assets"/*.glb "$assets"/*.gltf "$out/" && chmod 644 "$out"/*
node "$npm_dir/make_pose_fixtures.mjs" "$out"
for name in morph-sparse skins-shared morph-animated skins-animated; do
  "$transform" draco "$out/$name.gltf" "$out/$name.draco.glb"
  helper plain "$out/$name.draco.glb" "$out/$name.draco.plain.glb"
done
# gltfpack also compresses the animations' keyframes (resampled at 30 Hz, meshopt filters).
for name in morph-sparse morph-animated skins-animated; do
  "$gltfpack" -i "$out/$name.gltf" -o "$out/$name.meshopt.glb" -cc -noq
done
# The plain decodes are left out: Draco quantizes the float weights (lossily, as it may), so
# their sums miss 1 by 2e-4, which the validator reports; the compressed files pass.
helper validate "$out"/morph-*.gltf "$out"/morph-*.*[^n].glb "$out"/skins-*.gltf "$out"/skins-*.draco.glb "$out"/skins-animated.meshopt.glb

for file in "$out"/*.glb "$out"/*.gltf; do
  case "$file" in *.plain.glb) continue ;; esac
  source="$file"
  [ -f "${file%.glb}.plain.glb" ] && source="${file%.glb}.plain.glb"
  node "$npm_dir/pose_reference.mjs" "$source" "$out/three/$(basename "$file").json"
done

# Poses at three times (inside the keyframes, and past the end, where they clamp): every
# animation together, except Fox, whose three animations move the same joints (three.js would
# blend them): its Walk at the three times, Survey and Run at one.
timed() { # FILE TIME [ANIMATION]
  local suffix=".t$2" source="$out/$1"
  [ $# -gt 2 ] && suffix=".a$3$suffix"
  [ -f "${source%.glb}.plain.glb" ] && source="${source%.glb}.plain.glb"
  node "$npm_dir/pose_reference.mjs" "$source" "$out/three/$1$suffix.json" "${@:2}"
}
for file in AnimatedMorphCube.glb AnimatedTriangle.gltf BoxAnimated.glb CesiumMan.glb \
  InterpolationTest.glb RiggedFigure.glb SimpleSkin.gltf \
  morph-animated.gltf morph-animated.draco.glb morph-animated.meshopt.glb \
  skins-animated.gltf skins-animated.draco.glb skins-animated.meshopt.glb; do
  for time in 0.3 0.65 5; do timed "$file" "$time"; done
done
for time in 0.3 0.65 5; do timed Fox.glb "$time" 1; done
timed Fox.glb 0.65 0
timed Fox.glb 0.65 2
