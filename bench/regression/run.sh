#!/usr/bin/env bash
# Runs the regression set with one tactus-solve into OUT: the cube, two bars, incline, Hertz
# sphere, and ~500 steps of the hand-block case. Compare two such folders with compare.py.
#   run.sh TACTUS_SOLVE MESH_DIR HAND_WORK_DIR OUT
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
SOLVE=$1
MESHES=$2
HAND=$3
OUT=$4
mkdir -p "$OUT"
for c in two_bars incline hertz; do
  "$SOLVE" "$HERE/$c.toml" --meshes "$MESHES" -o "$OUT/$c" -q
done
"$SOLVE" "$HERE/../cases/cube.toml" --meshes "$MESHES" -o "$OUT/cube" -q
"$SOLVE" "$HERE/hand_block_touch.toml" --meshes "$HAND" -o "$OUT/hand_block_touch" -q
echo "regression set written to $OUT"
