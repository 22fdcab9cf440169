#!/usr/bin/env bash
# The comparison with gltfpack at matched triangles: for each LOD of frond's default chain
# (T triangles at screen height H), gltfpack -noq -si R with R = T / (input triangles) (plain
# -si at 600 px, -si R -sa at 200 and 60 px); both scored by
# `frond eval TREE X --screen-height H --json` (coverage.animated.mean). Prints a markdown
# table. Release build.
# Usage: bash docs/gltfpack_compare.sh OUT TREE.glb [TREE.glb ...]
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=$1
shift
F=target/release/frond
GLTFPACK=tools/node_modules/.bin/gltfpack
[ -x "$GLTFPACK" ] || (cd tools && npm ci --no-audit --no-fund --loglevel=error)
mkdir -p "$OUT"
score() { # TREE CANDIDATE H
  "$F" eval "$1" "$2" --screen-height "$3" --json 2>/dev/null |
    python3 -c 'import json,sys; print("%.4f" % json.load(sys.stdin)["coverage"]["animated"]["mean"])'
}
echo "| tree | H | frond T | frond error | gltfpack T | gltfpack error |"
echo "|---|---|---|---|---|---|"
for tree in "$@"; do
  name=$(basename "$tree" .glb)
  rm -rf "${OUT:?}/$name"
  "$F" lod "$tree" -o "$OUT/$name" --json >/dev/null 2>&1
  report="$OUT/$name/${name}_report.json"
  python3 - "$report" <<'EOF' >"$OUT/$name.lods"
import json, sys
r = json.load(open(sys.argv[1]))
lods = r["lods"]
input_t = lods[0]["cost"]["triangles"]
for k, l in enumerate(lods[1:], 1):
    print(k, int(l["screen_height"]), l["cost"]["triangles"], input_t, l["error"]["coverage"])
EOF
  while read -r k h t input_t frond_err; do
    r=$(python3 -c "print(min(1.0, $t / $input_t))")
    g="$OUT/${name}_gltfpack_$h.glb"
    if [ "$h" -ge 600 ]; then sa=""; else sa="-sa"; fi
    "$GLTFPACK" -i "$tree" -o "$g" -noq -si "$r" $sa >/dev/null 2>&1
    gt=$("$F" eval "$tree" "$g" --screen-height "$h" --json 2>/dev/null |
      python3 -c 'import json,sys; print(json.load(sys.stdin)["cost"]["candidate"]["triangles"])')
    printf "| %s | %s | %s | %.4f | %s | %s |\n" "$name" "$h" "$t" "$frond_err" "$gt" "$(score "$tree" "$g" "$h")"
  done <"$OUT/$name.lods"
done
