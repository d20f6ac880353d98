#!/usr/bin/env bash
# Sets tactus up (see setup.sh) and runs the main job on the bundled sample, stage by stage,
# until the one-command pipeline lands:
#   1. tactus-phantom  synthetic hand CT at the paper's resolution (0.7 mm) -> out/phantom/
#   2. tactus-segment  labels (soft tissue + 27 bones) and surfaces         -> out/segment/
#   3. tactus-mesh     conforming tet mesh of the segmented hand (CGAL) and the block (gmsh) -> out/mesh/
#   4. tactus-solve    the solver on its bundled scenario (a soft-tissue pad on a bone plate,
#                      pressed from above; hand-block impact needs the contact stage) -> out/pad_press/
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD=${TACTUS_BUILD_DIR:-$ROOT/build}
bash "$ROOT/scripts/setup.sh"
cd "$ROOT"
mkdir -p out/meshes
echo "== 1/4 phantom: synthetic hand CT (0.7 mm slices, noise 25 HU)"
"$BUILD/data_samples/tactus-phantom" -o out/phantom
echo "== 2/4 segment: soft tissue, bones, surfaces"
"$BUILD/segment/tactus-segment" out/phantom -o out/segment
echo "== 3/4 mesh: hand (CGAL, from the labels) and the paper's block (gmsh)"
"$BUILD/mesher/tactus-mesh" out/segment/labels.h5 -o out/mesh
"$BUILD/mesher/tactus-mesh" box --size 0.1 0.06 0.04 --element-size 0.008 -o out/mesh/block.msh
echo "== 4/4 solve: pipeline/scenarios/pad_press.toml"
"$BUILD/data_samples/tactus-sample-mesh" --size 0.04 0.04 0.012 --cells 16 16 6 \
  --inclusion -1 -1 -1 1 1 0.004 -o out/meshes/pad.msh
"$BUILD/solver/tactus-solve" pipeline/scenarios/pad_press.toml -o out/pad_press "$@"
echo
echo "CT slices and truth:   out/phantom/ (slice_NNNN.png, stack.json, truth.h5, truth.vti)"
echo "Segmentation:          out/segment/labels.h5, labels.vti, segment.json, surfaces/*.stl|ply"
echo "Meshes:                out/mesh/mesh.msh (+ .vtu, quality.json), out/mesh/block.msh"
echo "Simulation results:    out/pad_press/results.pvd (open in ParaView), history.csv, run.json"
