#!/usr/bin/env bash
# report/browser: a small contact run (tests/postproc/press.toml: a punch pressed into a pad)
# through tactus-solve and tactus-post, then its interactive report opened in headless Chromium
# and checked against the results folder (check_browser.py says what is checked).
# Usage: browser.sh <build dir>
set -euo pipefail
BUILD=$(cd "$1" && pwd)
SRC=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
[ -x /usr/bin/chromium ] || { echo "browser: FAIL: /usr/bin/chromium is missing (scripts/setup.sh installs Debian's chromium)"; exit 1; }
mkdir -p "$T/meshes"
"$BUILD/data_samples/tactus-sample-mesh" --size 0.02 0.02 0.006 --cells 10 10 3 -o "$T/meshes/pad.msh" -q
"$BUILD/data_samples/tactus-sample-mesh" --size 0.008 0.008 0.004 --origin 0.006 0.006 0.0063 --cells 4 4 2 \
  -o "$T/meshes/punch.msh" -q
"$BUILD/solver/tactus-solve" "$SRC/tests/postproc/press.toml" --meshes "$T/meshes" -o "$T/run" -q
"$BUILD/postproc/tactus-post" "$T/run" -o "$T/report" --no-pictures -q
/usr/bin/python3 "$SRC/tests/postproc/check_browser.py" "$T/run" "$T/report"
# The grip table of a grasp: the same run with two regions written into its run.json's joints.grasp
# (as the solver writes them; the numbers are the table's, not physics).
cp -r "$T/run" "$T/grasp"
/usr/bin/python3 - "$T/grasp/run.json" <<'PY'
import json
import sys

j = json.load(open(sys.argv[1]))
region = {"digit": "index", "normal_force": 30.0, "share": 0.6, "area": 1.5e-4, "peak_pressure": 4e5, "averaged_peak_pressure": 3e5}
regions = [dict(region, name="distal_phalanx_index"), dict(region, name="palm_central", digit="palm", normal_force=20.0, share=0.4)]
digits = [{"name": "index", "normal_force": 30.0, "share": 0.6}, {"name": "palm", "normal_force": 20.0, "share": 0.4}]
grasp = {"handle": "punch", "target_force": 50.0, "final_grip_force": 49.0, "quasi_static": True, "hold_from": 0.15}
grasp["regions"] = {"regions": regions, "digits": digits, "pressure_average_area": 2.5e-5}
j["joints"] = {"joints": [], "grasp": grasp}
json.dump(j, open(sys.argv[1], "w"))
PY
"$BUILD/postproc/tactus-post" "$T/grasp" -o "$T/grasp_report" --no-pictures -q
/usr/bin/python3 "$SRC/tests/postproc/check_browser.py" "$T/grasp" "$T/grasp_report" --grasp
