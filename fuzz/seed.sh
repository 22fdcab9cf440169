#!/usr/bin/env bash
# Fills fuzz/corpus/<target>/ (gitignored) with seed inputs for every fuzz target:
#   - a dozen tiny hand-built trees (1-11 KB; `seedgen tiny`, see seedgen/src/main.rs),
#   - generator trees (`frond sample --preset small --seed N`, via the generator API),
#     shrunk (`seedgen shrink`: whole JSON kept, <= 48 vertices per primitive, <= 6 keys per
#     sampler, 4x4 images) because the full ones (~430 KB) exceed the fuzzers' -max_len,
#   - samples/sapling.glb, shrunk the same way,
#   - the shared trees in ${FROND_TEST_TREES:-../shared/data/trees}, shrunk; any still larger
#     than FROND_FUZZ_MAX_LEN (default 262144 bytes) is skipped, with a message.
# Usage: fuzz/seed.sh [target...]   (default: import_glb import_structured lod_chain)
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(dirname "$here")"
trees="${FROND_TEST_TREES:-$root/../shared/data/trees}"
max_len="${FROND_FUZZ_MAX_LEN:-262144}"
if [ "$#" -gt 0 ]; then targets=("$@"); else targets=(import_glb import_structured lod_chain); fi

cargo build --release --quiet --manifest-path "$here/Cargo.toml" -p frond-fuzz-seedgen
seedgen="$here/target/release/frond-fuzz-seedgen"

tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/seeds"

"$seedgen" tiny "$tmp/seeds"
for seed in 2 3 4; do
    "$seedgen" generate small "$seed" "$tmp/gen_small_$seed.glb"
    "$seedgen" shrink "$tmp/gen_small_$seed.glb" "$tmp/seeds/gen_small_${seed}_shrunk.glb"
done
# A less aggressive shrink of one generator tree: more geometry for classification/binding.
"$seedgen" shrink "$tmp/gen_small_2.glb" "$tmp/seeds/gen_small_2_shrunk400.glb" 400 12

if [ -f "$root/samples/sapling.glb" ]; then
    "$seedgen" shrink "$root/samples/sapling.glb" "$tmp/seeds/sapling_shrunk.glb"
fi

if [ -d "$trees" ]; then
    for f in "$trees"/*.glb; do
        [ -e "$f" ] || continue
        name="$(basename "$f" .glb)"
        out="$tmp/seeds/shared_${name}_shrunk.glb"
        if ! "$seedgen" shrink "$f" "$out"; then
            echo "seed.sh: skipping $f (cannot shrink it)" >&2
            continue
        fi
        size=$(stat -c %s "$out")
        if [ "$size" -gt "$max_len" ]; then
            echo "seed.sh: skipping $f: still $size bytes after shrinking (> max_len $max_len)" >&2
            rm -f "$out"
        fi
    done
else
    echo "seed.sh: no shared trees at $trees (set FROND_TEST_TREES); using the others only" >&2
fi

for t in "${targets[@]}"; do
    mkdir -p "$here/corpus/$t"
    cp "$tmp"/seeds/* "$here/corpus/$t/"
    echo "seed.sh: $(ls "$tmp/seeds" | wc -l) seeds -> fuzz/corpus/$t ($(du -sh "$here/corpus/$t" | cut -f1) in the directory)"
done
"$seedgen" check "$tmp"/seeds/*
echo "seed.sh: (tiny_text.gltf names an external image.png; the fuzz harness provides one next to its input, 'check' here does not)"
