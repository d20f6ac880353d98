#!/usr/bin/env bash
# pipeline/handle: the second pipeline scenario, another object through the same generic stages.
# A cylinder handle STL (generated here by scripts/make_cylinder_stl.py) next to a copy of
# pipeline/scenarios/hand_handle.toml; tactus-pipeline meshes the phantom hand and the handle as
# the scenario's [[pipeline.meshes]] declare, solves 0.6 ms (the 0.5 mm gap closes at 0.25 ms) and
# reports. Checks: the report's numbers against the solver's files (check_report.py), contact
# occurred, the pressure is mapped on the hand (the contact's slave body, found from the data) and the
# pictures show it (check_pictures.py); a changed STL re-meshes the handle but not the hand.
# Then a 3-diameter design study (tactus-pipeline --study) of the same scenario with the handle as
# kind = "cylinder": the hand mesh is shared (not meshed again), each radius gets its own handle,
# solve and report, study/comparison.md lists all three; a rerun with one radius changed redoes
# only that one.
# Usage: handle.sh <build dir>
set -euo pipefail
BUILD=$(cd "$1" && pwd)
SRC=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
PY=/usr/bin/python3
T=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$T"' EXIT; echo "work: $T"
export TACTUS_BUILD_DIR=$BUILD
fail() { echo "handle: FAIL: $*"; exit 1; }

"$BUILD/data_samples/tactus-phantom" --voxel-mm 1.2 --slice-mm 1.2 -q -o "$T/phantom"
mkdir "$T/case"
cp "$SRC/pipeline/scenarios/hand_handle.toml" "$T/case/"
# Coarser than the scenario's comment (CI): 24 facets around, 8 mm elements.
"$PY" "$SRC/scripts/make_cylinder_stl.py" "$T/case/handle.stl" --radius 15 --length 120 --centre 0 -20 150 --segments 24
sed -i 's/--element-size 0.006/--element-size 0.008/' "$T/case/hand_handle.toml"
MESH_ARGS="--cell-size 9 --facet-size 5 --bone-facet-size 4 --bone-cell-size 5 --facet-distance 0.8"
run() { "$PY" "$SRC/pipeline/tactus-pipeline" "$T/phantom" "$T/case/hand_handle.toml" -o "$T/work" --end-time 6e-4 --mesh-args "$MESH_ARGS" -q; }

echo "--- 1. hand-handle to 0.6 ms"
run | tee "$T/first.log"
[ -f "$T/work/object/handle.msh" ] || fail "the handle was not meshed where the scenario says"
"$PY" "$SRC/tests/pipeline/check_report.py" "$T/work/solve" "$T/work/report" --expect-contact
"$PY" "$SRC/tests/pipeline/check_pictures.py" "$T/work/report" --pressure-body hand

echo "--- 2. a changed STL: the handle is meshed again, the hand is not"
"$PY" "$SRC/scripts/make_cylinder_stl.py" "$T/case/handle.stl" --radius 14 --length 120 --centre 0 -20 150 --segments 24
run | tee "$T/second.log"
grep -q "mesh mesh/mesh.msh: unchanged, skipped" "$T/second.log" || fail "the hand was meshed again"
grep -q "== mesh object/handle.msh: done" "$T/second.log" || fail "the handle was not meshed again after its STL changed"
grep -q "== solve: done" "$T/second.log" || fail "the solve did not re-run"
echo "--- 3. a 3-diameter study of the cylinder handle (28 / 30 / 32 mm)"
sed -e 's/^kind = "stl"/kind = "cylinder"/' -e 's/^file = "handle.stl".*/radius = 0.015\nlength = 0.12/' \
  -e 's/^args = .*/args = "--axis z --centre 0 -0.02 0.15 --element-size 0.008"/' \
  "$T/case/hand_handle.toml" >"$T/case/hand_cylinder.toml"
grep -q 'kind = "cylinder"' "$T/case/hand_cylinder.toml" || fail "the scenario's handle entry was not switched to a cylinder"
study() {
  "$PY" "$SRC/pipeline/tactus-pipeline" "$T/phantom" "$T/case/hand_cylinder.toml" -o "$T/work" --end-time 6e-4 --mesh-args "$MESH_ARGS" -q \
    --study "pipeline.meshes.1.radius=$1"
}
study 0.014,0.015,0.016 | tee "$T/study.log"
grep -q "mesh mesh/mesh.msh: unchanged, skipped" "$T/study.log" || fail "the study meshed the hand again"
for r in 0.014 0.015 0.016; do
  grep -q "== mesh object/handle.msh \[radius=$r\]: done" "$T/study.log" || fail "radius $r: its handle was not meshed"
  grep -q "^| $r | " "$T/work/study/comparison.md" || fail "radius $r is not in the comparison"
  [ -L "$T/work/study/radius=$r/mesh/mesh.msh" ] || fail "radius $r: the hand mesh is not the shared one"
done
"$PY" - "$T/work/study/comparison.json" <<'PY'
import json, sys
rows = json.load(open(sys.argv[1]))["values"]
forces = [r["figures"]["peak_contact_force_N"] for r in rows]
print("study: radius", [r["value"] for r in rows], "peak contact force (N)", forces)
assert all(f and f > 0 for f in forces), "a radius without contact"
PY
cat "$T/work/study/comparison.md"
echo "--- 4. one radius changed (0.016 -> 0.017): only that one runs"
study 0.014,0.015,0.017 | tee "$T/study2.log"
for r in 0.014 0.015; do
  grep -q "solve \[radius=$r\]: unchanged, skipped" "$T/study2.log" || fail "radius $r was solved again"
done
grep -q "== solve \[radius=0.017\]: done" "$T/study2.log" || fail "the new radius was not solved"
grep -q "^| 0.017 | " "$T/work/study/comparison.md" || fail "the new radius is not in the comparison"
echo "handle: all good"
