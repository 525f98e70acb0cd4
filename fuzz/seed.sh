#!/bin/sh
# Fills fuzz/corpus/<target>/ with seed inputs from the fixtures (files under 64 KiB),
# fuzz/seeds/<target>/ (for ply and stl: the corpus their first runs grew, kept whole) and
# fuzz/seeds/<target>-corpus.tar.xz (obj, usd, gltf: the corpus their 10^6-execution
# campaigns grew, reduced by libFuzzer's -set_cover_merge=1; reports/fuzzing.md).
# Run from the repository root: fuzz/seed.sh
set -eu
seed() {
    target=$1
    pattern=$2
    shift 2
    mkdir -p "fuzz/corpus/$target"
    find "$@" -type f -size -64k | grep -E "$pattern" | while read -r f; do
        cp "$f" "fuzz/corpus/$target/$(echo "$f" | tr '/' '_')"
    done
}
seed gltf '\.(gltf|glb)$' fixtures/gltf fixtures/gltf-validator fixtures/malformed fixtures/bad fixtures/compressed
seed obj '\.obj$' fixtures/obj fixtures/bad fixtures/assets fuzz/seeds/obj
seed usd '\.(usda|usdc|usd)$' fixtures/usd
seed ply '\.ply$' fixtures/ply fixtures/bad
seed ply '' fuzz/seeds/ply
seed stl '\.stl$' fixtures/stl fixtures/bad
seed stl '' fuzz/seeds/stl
for t in obj usd gltf; do
    tar -xJf "fuzz/seeds/$t-corpus.tar.xz" -C "fuzz/corpus/$t" --strip-components=1
done
for t in gltf obj usd ply stl; do
    echo "$t: $(ls "fuzz/corpus/$t" | wc -l) seeds"
done
