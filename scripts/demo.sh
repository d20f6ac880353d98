#!/usr/bin/env bash
# Sets tactus up (see setup.sh) and runs the main job on the bundled sample. Until the
# segmentation, meshing and post-processing stages land, the main job is the solver stage on
# its bundled scenario: a soft-tissue pad (HGO, the paper's parameters) on a bone plate, pressed
# from above (pipeline/scenarios/pad_press.toml). Outputs go to out/.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD=${TACTUS_BUILD_DIR:-$ROOT/build}
bash "$ROOT/scripts/setup.sh"
cd "$ROOT"
mkdir -p out/meshes
echo "== mesh: structured sample pad (soft tissue over a 4 mm bone plate)"
"$BUILD/data_samples/tactus-sample-mesh" --size 0.04 0.04 0.012 --cells 16 16 6 \
  --inclusion -1 -1 -1 1 1 0.004 -o out/meshes/pad.msh
echo "== solve: pipeline/scenarios/pad_press.toml"
"$BUILD/solver/tactus-solve" pipeline/scenarios/pad_press.toml -o out/pad_press "$@"
echo
echo "Results: out/pad_press/results.pvd (open in ParaView), out/pad_press/history.csv, out/pad_press/run.json"
