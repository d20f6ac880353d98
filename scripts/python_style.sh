#!/usr/bin/env bash
# Python style of pipeline/, scripts/, bench/ and tests/: Debian 12's black (pyproject.toml) and
# flake8 (.flake8) at one line length. --fix reformats with black first.
#   scripts/python_style.sh [--fix]
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
mapfile -t files < <(git ls-files '*.py' 2> /dev/null || find pipeline scripts bench tests -name '*.py')
files+=(pipeline/tactus-pipeline)
for tool in black; do command -v $tool > /dev/null || { echo "python style: $tool is not installed (scripts/setup.sh installs it)"; exit 1; }; done
/usr/bin/python3 -m flake8 --version > /dev/null 2>&1 || { echo "python style: flake8 is not installed (python3-flake8; scripts/setup.sh installs it)"; exit 1; }
if [ "${1:-}" = --fix ]; then black -q "${files[@]}"; fi
black --check -q "${files[@]}" || { echo "python style: not formatted (run scripts/python_style.sh --fix)"; exit 1; }
/usr/bin/python3 -m flake8 "${files[@]}"
echo "python style: ${#files[@]} files clean (black, flake8)"
