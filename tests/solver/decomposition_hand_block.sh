#!/usr/bin/env bash
# The hand-block model (the pinned reference meshes of bench/references: the demo's 70k-tet hand
# and its block) split by tactus-solve decompose at 4 and 8 ranks: the load imbalance (heaviest
# rank's stress-pass cost over the mean, minus 1) must be at most 5 %; the edge cut is printed.
set -euo pipefail
BUILD=$1
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
TACTUS_BUILD_DIR=$BUILD bash "$ROOT/bench/references/hand_block_meshes.sh" "$WORK" > /dev/null
ok=1
for ranks in 4 8; do
  out=$("$BUILD/solver/tactus-solve" decompose "$ROOT/pipeline/scenarios/hand_block.toml" --meshes "$WORK" --ranks "$ranks")
  echo "$out"
  imbalance=$(echo "$out" | sed -n 's/.*load imbalance \([0-9.e+-]*\) %.*/\1/p')
  if ! awk -v x="$imbalance" 'BEGIN { exit !(x <= 5) }'; then
    echo "decomposition: $ranks ranks: load imbalance $imbalance % above 5 %" >&2
    ok=0
  fi
done
[ "$ok" = 1 ]
