#!/bin/bash
# Usage: tools/identity/run.sh BIN OUT
#
# Runs one frond binary over a fixed set of commands (frond lod with every method and every
# animation mode on the sample and two shared trees, frond cloud, frond eval --json, and
# frond sweep --lods 600,200,60 --seeds 2) and writes everything under OUT. Run it with the
# binary before and after a refactor, then compare the two folders with compare.py: a
# refactor that changes no behaviour gives identical files, timing fields aside.
set -u
BIN=$(realpath "$1"); OUT=$2
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
T=$(realpath "${FROND_TEST_TREES:-$ROOT/../shared/data/trees}")
rm -rf "$OUT"; mkdir -p "$OUT"; OUT=$(realpath "$OUT")
S=$ROOT/samples/sapling.glb
run() { echo "+ $*" >>"$OUT/log"; "$BIN" "$@" >>"$OUT/log" 2>&1 || echo "FAILED $*" >>"$OUT/log"; }
for m in auto per-bone static spectral spectral-naive spectral-dominating-axis spectral-axis-phase skeleton skeleton-axis-angle skeleton-rotation-spectral; do
  run lod $S -o $OUT/sap_$m --method $m
done
for a in vat vat-png16; do for m in spectral skeleton per-bone static; do run lod $S -o $OUT/sap_${m}_$a --method $m --animation $a; done; done
for m in spectral per-bone; do run lod $S -o $OUT/sap_${m}_spectral --method $m --animation spectral; done
run lod $S -o $OUT/sap_opts --method spectral --epsilon 1% --zone-size 3% --clusters 4 --msft-lod --external-textures
run lod $S -o $OUT/sap_sk_opts --method skeleton --clouds 3 --average-bone --distances 5,20,80
for t in bush_1 pine_medium_blender; do
  for m in auto spectral skeleton per-bone; do run lod $T/$t.glb -o $OUT/${t}_$m --method $m; done
  run lod $T/$t.glb -o $OUT/${t}_vat --method spectral --animation vat
  run lod $T/$t.glb -o $OUT/${t}_spec --method spectral --animation spectral
  run cloud $T/$t.glb -o $OUT/${t}_cloud
done
run cloud $S -o $OUT/sap_cloud
# eval: the spectral and skeleton LODs against the input
for d in sap_spectral sap_skeleton sap_per-bone_vat; do for f in $OUT/$d/*_LOD1.glb $OUT/$d/*_LOD3.glb; do
  [ -f "$f" ] && { "$BIN" eval $S "$f" --json >"$OUT/eval_$(basename $d)_$(basename $f .glb).json" 2>>"$OUT/log" || echo "FAILED eval $f" >>"$OUT/log"; }
done; done
for t in bush_1 pine_medium_blender; do for f in $OUT/${t}_spectral/*_LOD2.glb $OUT/${t}_skeleton/*_LOD2.glb; do
  "$BIN" eval $T/$t.glb "$f" --json >"$OUT/eval_$(basename $f .glb)_$t.json" 2>>"$OUT/log" || echo "FAILED eval $f" >>"$OUT/log"
done; done
run sweep $S -o $OUT/sweep --lods 600,200,60 --seeds 2
echo done >>"$OUT/log"
