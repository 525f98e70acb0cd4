#!/usr/bin/env bash
# Remakes fixtures/compressed/: Draco (sequential and edgebreaker), meshopt (EXT_ and KHR_ names,
# octahedral, quaternion and exponential filters, with and without fallback buffers), quantized
# and GPU-instanced versions of real assets, each with the reference decode that the official
# decoders give (`*.plain.glb`, written by glTF-Transform with draco3dgltf and meshoptimizer).
#
# Tools are pinned in tools/npm/package-lock.json (gltfpack, @gltf-transform/cli, gltf-validator);
# this script installs them with `npm ci` when missing. Inputs come from the shared asset folder
# (../shared/assets, or $RAYCAST_ASSETS): DamagedHelmet, chr_knight, ShapeCollection, many-cubes.
# Every output is checked with the Khronos glTF-Validator and must have no error.
set -euo pipefail

repo=$(cd "$(dirname "$0")/.." && pwd)
npm_dir="$repo/tools/npm"
assets=${RAYCAST_ASSETS:-$repo/../shared/assets}/gltf
out="$repo/fixtures/compressed"
[ -d "$assets" ] || { echo "make_compressed_fixtures: no asset folder at $assets" >&2; exit 1; }
[ -x "$npm_dir/node_modules/.bin/gltfpack" ] || (cd "$npm_dir" && npm ci --no-audit --no-fund)

gltfpack="$npm_dir/node_modules/.bin/gltfpack"
transform="$npm_dir/node_modules/.bin/gltf-transform"
helper() { node "$npm_dir/gltf_helper.mjs" "$@"; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"
rm -f "$out"/*.glb "$out"/*.bin

# Sources, small and without textures (a ray caster reads none): the helmet is simplified
# to about 4.5k triangles with gltfpack's simplifier, the others keep all their triangles.
helper strip "$assets/DamagedHelmet.glb" "$work/helmet_textured.glb"
"$gltfpack" -i "$work/helmet_textured.glb" -o "$work/helmet.glb" -noq -si 0.1
helper strip "$assets/chr_knight.glb" "$work/knight.glb"
cp "$assets/ShapeCollection.glb" "$work/shapes.glb"
"$gltfpack" -i "$assets/many-cubes.gltf" -o "$out/cubes.nodes.glb" -noq

# Draco, both connectivity methods (glTF-Transform with draco3dgltf).
for name in helmet knight shapes; do
  "$transform" draco "$work/$name.glb" "$out/$name.draco-seq.glb" --method sequential
  "$transform" draco "$work/$name.glb" "$out/$name.draco-eb.glb" --method edgebreaker
done
# Draco used but not required, with empty fallback accessors.
helper draco-optional "$out/knight.draco-seq.glb" "$out/knight.draco-optional.glb"

# meshopt: -cc adds the octahedral filter (normals), -vpf stores float positions through the
# exponential filter, -mi makes instances whose rotations use the quaternion filter.
"$gltfpack" -i "$work/helmet.glb" -o "$out/helmet.meshopt.glb" -cc -vpf
"$gltfpack" -i "$work/helmet.glb" -o "$out/helmet.meshopt-khr.glb" -cc -ce khr
"$gltfpack" -i "$work/shapes.glb" -o "$out/shapes.meshopt.glb" -cc -kn
"$gltfpack" -i "$work/knight.glb" -o "$out/knight.meshopt-fallback.glb" -cf
"$transform" meshopt "$work/knight.glb" "$out/knight.meshopt.glb"

# Quantized without compression (KHR_mesh_quantization).
"$gltfpack" -i "$work/helmet.glb" -o "$out/helmet.quantized.glb"
"$gltfpack" -i "$work/shapes.glb" -o "$out/shapes.quantized.glb" -kn

# GPU instancing: many-cubes' 501 nodes sharing one mesh become one node with 501 instances.
# Unquantized (-noq), so that trimesh can be the reference for tools/validate.py.
"$gltfpack" -i "$assets/many-cubes.gltf" -o "$out/cubes.instanced.glb" -mi -noq
"$gltfpack" -i "$assets/many-cubes.gltf" -o "$out/cubes.instanced-meshopt.glb" -mi -cc

# Reference decodes: the official decoders' output as plain accessors. The quantized files'
# reference is glTF-Transform's dequantization (float positions, the quantization folded out
# of the node transforms).
for file in "$out"/*.glb; do
  case "$file" in
    *.plain.glb | *.nodes.glb | *.instanced.glb) ;; # nothing to decode
    *.draco-optional.glb) ;; # the Draco stream of knight.draco-seq.glb
    *.quantized.glb) "$transform" dequantize "$file" "${file%.glb}.plain.glb" ;;
    *) helper plain "$file" "${file%.glb}.plain.glb" ;;
  esac
done

# Draco used but not required, with fallback accessors holding the reference decode.
helper draco-fallback "$out/knight.draco-seq.glb" "$out/knight.draco-seq.plain.glb" \
  "$out/knight.draco-fallback.glb"

helper validate "$out"/*.glb
du -b "$out"/*.glb | sort -k2
