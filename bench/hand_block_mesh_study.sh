#!/usr/bin/env bash
# The hand-block case on the default meshes and on meshes refined by 0.7x in element size (the
# hand's surface and cell sizes and the block's element size: with the block's mesh unchanged the
# late contact area kept growing, 1,018 -> 1,414 mm^2 at 5 ms): contact force, area and the 25 mm^2 peak
# pressure at each output, side by side, with the differences the contact issue asks for (force
# and area within 10 %, 25 mm^2 peak within 15 %), the same for the windowed force and area, and
# each run's contact impulse over the whole run and between outputs (the time integral of the
# normal force: on this case it settles with the mesh where the instantaneous figures scatter).
#   bench/hand_block_mesh_study.sh [--scenario FILE] [--levels 2|3] [--ensemble N] [--smooth-boundaries SIGMA]
#                                  [--pressure-window TAU] [--refine-box "X0 Y0 Z0 X1 Y1 Z1" --refine-size S]
#                                  [--cell-scale C] [labels.h5]
#     labels.h5    default: the demo's out/pipeline/segment/labels.h5
#   Without options the default level is tactus-mesh's defaults (the coarse mesh); the demo's mesh
#   (hand_block.toml's [[pipeline.meshes]] args) is the default level of
#     --cell-scale 0.7 --refine-box "36 -40 30 49 20 200" --refine-size 1 --smooth-boundaries 1
#   (README's table; hand_block.toml sets the 0.25 ms pressure window itself).
#     --scenario   default: pipeline/scenarios/hand_block.toml. With rigid bones the study is
#                  cheaper (pipeline/scenarios/hand_block_rigid.toml), and a copy with
#                  `formulation = "standard"` or `pressure_smoothing = 0` compares the soft-tissue tets.
#     --levels 3   also a mesh refined by 0.49x (about 150k tets).
#     --ensemble N N runs per mesh, the first as given, the others with the bodies' initial
#                  velocities scaled by 1 + k 1e-6 (k = 1 .. N-1): a change of the input far below
#                  anything physical, so the spread of the results over the N runs is how much the
#                  impact amplifies a last-bit difference (the step's, the summation order's). Prints
#                  each figure's mean and spread per mesh and the meshes' difference of means beside
#                  the spread: a difference between meshes below the spread cannot be told from it.
#     --smooth-boundaries SIGMA  the hand meshed with tactus-mesh --smooth-boundaries SIGMA (voxels):
#                  boundaries on Gaussian-smoothed label indicators instead of the voxels' staircase.
#     --refine-box "X0 Y0 Z0 X1 Y1 Z1" --refine-size S  the hand's contact zone (world mm) meshed with
#                  facets of S mm on the default mesh, 0.7 S and 0.49 S on the finer ones (tactus-mesh
#                  --refine-box; facet distance 0.1 S there), e.g. "38 -40 30 49 5 200" and 1 for the
#                  demo hand's ulnar edge.
#     --cell-scale C  every level's soft-tissue and bone cell sizes (the mesh's inside) times C,
#                  the surface sizes kept: with C = 0.7 the default level has the 0.7x mesh's cells
#                  (4.9 / 2.45 mm) under its own 4 / 3 mm facets.
#     --pressure-window TAU  the scenario's contact_solver.pressure_window set to TAU seconds: the reported
#                  pressure (and with it the 25 mm^2 peak) and the windowed force and area become
#                  exponential averages over TAU, like a sensor of that time constant (e.g. 2.5e-4, the
#                  bandwidth of the +-0.25 ms force and area; the default 1e-5 passes the ringing).
# Environment: TACTUS_BUILD_DIR (default build/), WORK (default a temporary folder). On 2 cores
# about 3 min for two levels of the rigid-bone case, 5 min with deformable bones (smoothed ANP);
# the third level takes 5-10 min with rigid bones, 9 min with deformable ones.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
B=${TACTUS_BUILD_DIR:-$ROOT/build}
SCENARIO=$ROOT/pipeline/scenarios/hand_block.toml
LEVELS=2
CELL_SCALE=1
ENSEMBLE=1
SMOOTH=()
WINDOW=
REFINE_BOX=
REFINE_SIZE=
LABELS=$ROOT/out/pipeline/segment/labels.h5
while [ $# -gt 0 ]; do
  case "$1" in
    --scenario) SCENARIO=$(cd "$(dirname "$2")" && pwd)/$(basename "$2"); shift 2 ;;
    --levels) LEVELS=$2; shift 2 ;;
    --cell-scale) CELL_SCALE=$2; shift 2 ;;
    --ensemble) ENSEMBLE=$2; shift 2 ;;
    --smooth-boundaries) SMOOTH=(--smooth-boundaries "$2"); shift 2 ;;
    --pressure-window) WINDOW=$2; shift 2 ;;
    --refine-box) REFINE_BOX=$2; shift 2 ;;
    --refine-size) REFINE_SIZE=$2; shift 2 ;;
    -*) echo "usage: bench/hand_block_mesh_study.sh [--scenario FILE] [--levels 2|3] [--ensemble N] [--smooth-boundaries SIGMA] [--pressure-window TAU] [--refine-box \"X0 Y0 Z0 X1 Y1 Z1\" --refine-size S] [--cell-scale C] [labels.h5]" >&2; exit 2 ;;
    *) LABELS=$1; shift ;;
  esac
done
[ "$LEVELS" = 2 ] || [ "$LEVELS" = 3 ] || { echo "--levels: 2 or 3" >&2; exit 2; }
/usr/bin/python3 -c "import sys; sys.exit(0 if 0 < float('$CELL_SCALE') <= 1 else 1)" 2>/dev/null || { echo "--cell-scale: a number in (0, 1]" >&2; exit 2; }
[[ "$ENSEMBLE" =~ ^[1-9]$ ]] || { echo "--ensemble: 1 to 9 runs per mesh" >&2; exit 2; }
[ -f "$SCENARIO" ] || { echo "no scenario $SCENARIO" >&2; exit 2; }
if [ -n "$REFINE_BOX$REFINE_SIZE" ] && { [ -z "$REFINE_BOX" ] || [ -z "$REFINE_SIZE" ]; }; then
  echo "--refine-box and --refine-size go together" >&2
  exit 2
fi
[ -f "$LABELS" ] || { echo "no $LABELS: run scripts/demo.sh first, or pass a labels.h5" >&2; exit 2; }
W=${WORK:-$(mktemp -d)}
[ -z "${WORK:-}" ] && trap 'rm -rf "$W"' EXIT
mkdir -p "$W"
source "$ROOT/bench/study_common.sh"
SCENARIO=$(study_scenario_with_window "$SCENARIO" "$WINDOW")
names=(default fine)
[ "$LEVELS" = 3 ] && names+=(finer)
for name in "${names[@]}"; do
  study_level_folder "$name"
  case $name in default) f=1 block=0.008 ;; fine) f=0.7 block=0.0056 ;; finer) f=0.49 block=0.00392 ;; esac
  # tactus-mesh's default sizes (facets 4 mm, bone 3 mm, cells 7 mm, bone 3.5 mm, facet distance
  # 0.6 mm) times the level's factor, the cells also times --cell-scale.
  sizes=(--facet-size "$(study_scaled 4 "$f")" --bone-facet-size "$(study_scaled 3 "$f")" --cell-size "$(study_scaled "7 * $CELL_SCALE" "$f")"
    --bone-cell-size "$(study_scaled "3.5 * $CELL_SCALE" "$f")" --facet-distance "$(study_scaled 0.6 "$f")")
  refine=()
  if [ -n "$REFINE_SIZE" ]; then
    read -r -a corners <<<"$REFINE_BOX"
    refine=(--refine-box "${corners[@]}" --refine-size "$(study_scaled "$REFINE_SIZE" "$f")"
      --refine-distance "$(study_scaled "0.1 * $REFINE_SIZE" "$f")")
  fi
  "$B/mesher/tactus-mesh" "$LABELS" "${sizes[@]}" "${SMOOTH[@]}" "${refine[@]}" -o "$W/$name/mesh/mesh.msh" -q
  study_fibres_block_solve "$name" "$block" "$SCENARIO"
  for ((k = 1; k < ENSEMBLE; k++)); do
    # The same scenario with every initial_velocity scaled by 1 + k 1e-6 (mesh paths resolve from --meshes).
    /usr/bin/python3 - "$SCENARIO" "$W/$name/scenario_$k.toml" "$k" <<'PY'
import re, sys
text, k = open(sys.argv[1]).read(), int(sys.argv[3])
def scaled(m):
    values = [float(v) * (1 + k * 1e-6) for v in m.group(2).split(",")]
    return m.group(1) + ", ".join(repr(v) for v in values) + "]"
text, n = re.subn(r"^(\s*initial_velocity\s*=\s*\[)([^\]]*)\]", scaled, text, flags=re.M)
if n == 0:
    sys.exit(f"{sys.argv[1]}: no initial_velocity to perturb for --ensemble")
open(sys.argv[2], "w").write(text)
PY
    echo "== $name mesh: ensemble run $((k + 1)) of $ENSEMBLE (initial velocities x (1 + $k e-6))"
    "$B/solver/tactus-solve" "$W/$name/scenario_$k.toml" --meshes "$W/$name" -o "$W/$name/out_$k" -q
  done
done
/usr/bin/python3 "$ROOT/bench/mesh_study_report.py" "$ROOT/bench" "$W" "$ENSEMBLE" "${names[@]}"
