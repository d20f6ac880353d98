#!/usr/bin/env bash
# The real-CT speed bench (issue: "a 512 x 512 x 400 CT in seconds"): the phantom at 0.3 mm
# (566 x 306 x 786 voxels, 136 M: more than a 512 x 512 x 400 scan's 105 M) written as a DICOM
# series, then labels without surfaces, labels with surfaces, and the mesh at the default size,
# each with its wall time and peak memory (GNU time). Targets: labels <= 30 s within 4 GB,
# surfaces <= 60 s, mesh <= 60 s (for 105 M voxels).
#   bench/ct_bench.sh [voxel mm, default 0.3]
# Environment: TACTUS_BUILD_DIR (default build/), WORK (default a temporary folder, removed).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
B=${TACTUS_BUILD_DIR:-$ROOT/build}
W=${WORK:-$(mktemp -d)}
[ -z "${WORK:-}" ] && trap 'rm -rf "$W"' EXIT
VOXEL=${1:-0.3}
rm -rf "$W/dcm" "$W/labels" "$W/surfaces" "$W/mesh"
timed() {  # timed LABEL command...
  local label=$1
  shift
  /usr/bin/time -f "$label: %e s wall, %M KB peak" "$@"
}
timed "phantom -> DICOM" "$B/data_samples/tactus-phantom" --voxel-mm "$VOXEL" --slice-mm "$VOXEL" --format dicom -o "$W/dcm" -q
echo "DICOM series: $(ls "$W/dcm" | wc -l) files, $(du -sh "$W/dcm" | cut -f1)"
timed "labels (no surfaces)" "$B/segment/tactus-segment" "$W/dcm" -o "$W/labels" --no-surfaces -q
timed "labels + surfaces" "$B/segment/tactus-segment" "$W/dcm" -o "$W/surfaces" -q
timed "mesh (default size)" "$B/mesher/tactus-mesh" "$W/labels/labels.h5" -o "$W/mesh" -q
/usr/bin/python3 - "$W" <<'PY'
import json, sys
w = sys.argv[1]
s = json.load(open(f"{w}/labels/segment.json"))
n = s["dims"][0] * s["dims"][1] * s["dims"][2]
print(f"volume {s['dims']} = {n / 1e6:.0f} M voxels; labels stage: read {s['time_s']['read']:.1f} s, segment {s['time_s']['segment']:.1f} s; "
      f"{len(s['bones'])} bones")
q = json.load(open(f"{w}/mesh/quality.json"))["all"]
print(f"mesh: {q['tets']} tets, min dihedral {q['min_dihedral_deg']:.1f} deg, L_e min/median {q['min_over_median_length']:.3f}")
PY
