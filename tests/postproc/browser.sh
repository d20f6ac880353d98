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
