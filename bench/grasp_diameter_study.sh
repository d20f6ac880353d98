#!/usr/bin/env bash
# The grasp design study: the phantom hand (pre-flexed 35 degrees) grasps handles of 30, 40 and
# 50 mm diameter to the 50 N grip of pipeline/scenarios/hand_grasp.toml, in one
# `tactus-pipeline --study pipeline.meshes.2.radius=... --study grasp.handle_centre=...` (the hand
# segmented, meshed and its skeleton extracted once). Each handle's axis sits SURFACE + radius out
# of the palm frame's origin (the scenario's 40 mm handle at 65 mm: its surface 45 mm out), so
# every diameter starts the same distance from the curled fingers. Prints the study's comparison
# table (grip, handle contact area, 25 mm² and nodal peak pressure, KE/IE in the hold, each digit's
# share) and each value's solve time.
#   bench/grasp_diameter_study.sh [RADII [SURFACE]]   defaults "0.015,0.02,0.025" and 0.045 (m)
# Environment: TACTUS_BUILD_DIR (default build/), WORK (default a temporary folder). About 4 min
# of solve per value on 2 cores.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
B=${TACTUS_BUILD_DIR:-$ROOT/build}
RADII=${1:-0.015,0.02,0.025}
SURFACE=${2:-0.045}
CENTRES=$(/usr/bin/python3 -c "import sys; print(','.join(f'[0.0, -0.01, {float(sys.argv[2]) + float(r):.4g}]' for r in sys.argv[1].split(',')))" "$RADII" "$SURFACE")
W=${WORK:-$(mktemp -d)}
[ -z "${WORK:-}" ] && trap 'rm -rf "$W"' EXIT
mkdir -p "$W"
cp "$ROOT/pipeline/scenarios/hand_grasp.toml" "$W/"
[ -d "$W/phantom" ] || "$B/data_samples/tactus-phantom" --flexion 35 -o "$W/phantom" -q
status=0
"$ROOT/pipeline/tactus-pipeline" "$W/phantom" "$W/hand_grasp.toml" -o "$W/study" -q --study "pipeline.meshes.2.radius=$RADII" \
  --study "grasp.handle_centre=$CENTRES" || status=$?
cat "$W/study/study/comparison.md"
/usr/bin/python3 - "$W/study" <<'PY'
import json, os, sys
work = sys.argv[1]
for row in json.load(open(os.path.join(work, "study", "comparison.json")))["values"]:
    try:
        run = json.load(open(os.path.join(work, row["folder"], "solve", "run.json")))
        print(f"radius {row['value']} m: solve {run['wall_time_s']:.0f} s wall, {run['steps']} steps, {run['tets']} tets")
    except OSError:
        print(f"radius {row['value']} m: no run.json")
PY
exit $status
