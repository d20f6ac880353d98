#!/usr/bin/env bash
# Regression references of the bundled cases: runs each case and compares its figures with the
# stored reference (tactus-solve --check), printing every difference.
#   bench/references/check.sh [cube|pad_press|hand_block|all] [--update]
# --update rewrites the references from this run (do it in the commit that moves the numbers,
# and say why in its message). Environment: TACTUS_BUILD_DIR (default build/), WORK (default a
# temporary folder). hand_block runs on the stored meshes it was recorded with (the demo's refined mesh):
# about 2.5 min on 2 quiet cores.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
B=${TACTUS_BUILD_DIR:-$ROOT/build}
REF=$ROOT/bench/references
case_name=${1:-all}
mode=--check
[ "${2:-}" = "--update" ] && mode=--write-reference
W=${WORK:-$(mktemp -d)}
[ -z "${WORK:-}" ] && trap 'rm -rf "$W"' EXIT
mkdir -p "$W"

run_case() {  # run_case NAME SCENARIO MESH_DIR [more tactus-solve options]
  local name=$1 scenario=$2 meshes=$3
  shift 3
  echo "== $name"
  rm -rf "$W/$name.out"
  # --update: the stored reference is a file in the repository, not an output tactus wrote here;
  # asking for the update is asking to replace it.
  [ "$mode" = --write-reference ] && rm -f "$REF/$name.json"
  "$B/solver/tactus-solve" "$scenario" --meshes "$meshes" -o "$W/$name.out" -q "$mode" "$REF/$name.json" "$@"
}

if [ "$case_name" = cube ] || [ "$case_name" = all ]; then
  [ -f "$W/cube.msh" ] || "$B/data_samples/tactus-sample-mesh" --size 0.1 0.1 0.1 --cells 20 20 20 -o "$W/cube.msh" -q
  run_case cube "$ROOT/bench/cases/cube.toml" "$W"
fi
if [ "$case_name" = pad_press ] || [ "$case_name" = all ]; then
  [ -f "$W/pad.msh" ] || "$B/data_samples/tactus-sample-mesh" --size 0.04 0.04 0.012 --cells 16 16 6 \
    --inclusion -1 -1 -1 1 1 0.004 -o "$W/pad.msh" -q
  run_case pad_press "$ROOT/pipeline/scenarios/pad_press.toml" "$W"
fi
if [ "$case_name" = hand_block ] || [ "$case_name" = all ]; then
  # The demo's meshes as they were when the reference was recorded, stored next to it (see
  # hand_block_meshes.sh): the reference pins the meshes and checks the solver.
  TACTUS_BUILD_DIR=$B bash "$REF/hand_block_meshes.sh" "$W/hand_block"
  run_case hand_block "$ROOT/pipeline/scenarios/hand_block.toml" "$W/hand_block"
fi
