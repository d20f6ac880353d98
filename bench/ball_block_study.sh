#!/usr/bin/env bash
# The hand-block mesh study's figures on a smooth body: a ball of soft tissue (radius 15 mm) with a
# bone core (6 mm), at 2 m/s into the block, rigid bones and block (pipeline/scenarios/
# hand_block_rigid.toml: the same materials, contact pairs and outputs as the hand). Its label
# volume is written here (0.25 mm voxels) and meshed with smoothed boundaries, so the skin is a
# sphere at every level and the peak sits at the pole on every mesh: what the contact pressure at
# the 25 mm^2 sensor scale does under refinement without the segmented hand's voxel steps and
# near-tied sites (bench/hand_block_mesh_study.sh). Levels: surface facets 2, 1.4, 0.98 and
# (--levels 4) 0.69 mm, cells 2.5 mm and 0.7x each level, facet distance 0.15 mm x 0.7 each level.
#   bench/ball_block_study.sh [--levels 3|4] [--pressure-window TAU]
#     --pressure-window TAU  the scenario's contact_solver.pressure_window set to TAU seconds (e.g.
#                  2.5e-4, a sensor's time constant; default 1e-5)
# Environment: TACTUS_BUILD_DIR (default build/), WORK (default a temporary folder). On 2 cores
# about 1 min for three levels; the fourth (132k tets, 28,712 steps) adds a few minutes.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
B=${TACTUS_BUILD_DIR:-$ROOT/build}
LEVELS=3
WINDOW=
while [ $# -gt 0 ]; do
  case "$1" in
    --levels) LEVELS=$2; shift 2 ;;
    --pressure-window) WINDOW=$2; shift 2 ;;
    *) echo "usage: bench/ball_block_study.sh [--levels 3|4] [--pressure-window TAU]" >&2; exit 2 ;;
  esac
done
[ "$LEVELS" = 3 ] || [ "$LEVELS" = 4 ] || { echo "--levels: 3 or 4" >&2; exit 2; }
W=${WORK:-$(mktemp -d)}
[ -z "${WORK:-}" ] && trap 'rm -rf "$W"' EXIT
mkdir -p "$W"
SCENARIO=$ROOT/pipeline/scenarios/hand_block_rigid.toml
source "$ROOT/bench/study_common.sh"
SCENARIO=$(study_scenario_with_window "$SCENARIO" "$WINDOW")
# The ball's labels: 0 background, 1 soft tissue (r <= 15 mm), 2 bone (r <= 6 mm), centred at
# (0, -20, 120) mm inside the block's footprint, in the HDF5 layout tactus-segment writes.
/usr/bin/python3 - "$W/labels.h5" <<'PY'
import json, sys
import h5py
import numpy as np
h, radius, core = 0.25e-3, 15e-3, 6e-3
centre = np.array([0.0, -20e-3, 120e-3])
n = int(round(2 * (radius + 2e-3) / h))
origin = centre - (n - 1) / 2 * h
axis = h * np.arange(n)
x, y, z = (origin[0] + axis)[None, None, :], (origin[1] + axis)[None, :, None], (origin[2] + axis)[:, None, None]
r = np.sqrt((x - centre[0]) ** 2 + (y - centre[1]) ** 2 + (z - centre[2]) ** 2)
labels = np.zeros((n, n, n), np.uint8)  # z, y, x
labels[r <= radius] = 1
labels[r <= core] = 2
with h5py.File(sys.argv[1], "w") as f:
    d = f.create_dataset("labels", data=labels, chunks=(1, n, n), compression="gzip")
    d.attrs["axes"] = np.bytes_("z,y,x (attributes are x,y,z)")
    d.attrs["direction"] = np.eye(3).ravel()
    d.attrs["label_table"] = np.bytes_(json.dumps({"0": "background", "1": "soft_tissue", "2": "bone_02"}))
    d.attrs["origin"] = origin
    d.attrs["spacing"] = np.array([h, h, h])
    d.attrs["units"] = np.bytes_("m")
PY
names=(default fine finer)
[ "$LEVELS" = 4 ] && names+=(finest)
scale=1
for name in "${names[@]}"; do
  study_level_folder "$name"
  "$B/mesher/tactus-mesh" "$W/labels.h5" --smooth-boundaries 1 --facet-size "$(study_scaled 2.0 "$scale")" \
    --bone-facet-size "$(study_scaled 1.5 "$scale")" --cell-size "$(study_scaled 2.5 "$scale")" \
    --bone-cell-size "$(study_scaled 1.5 "$scale")" --facet-distance "$(study_scaled 0.15 "$scale")" -o "$W/$name/mesh/mesh.msh" -q
  echo "== $name mesh (sizes x $(/usr/bin/python3 -c "print(f'{$scale:.3g}')"))"
  study_fibres_block_solve "$name" 0.008 "$SCENARIO"
  scale=$(/usr/bin/python3 -c "print($scale * 0.7)")
done
/usr/bin/python3 "$ROOT/bench/mesh_study_report.py" "$ROOT/bench" "$W" 1 "${names[@]}"
