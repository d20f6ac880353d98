#!/usr/bin/env bash
# Sets up (see setup.sh) and runs the whole test suite through CTest.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD=${TACTUS_BUILD_DIR:-$ROOT/build}
bash "$ROOT/scripts/setup.sh"
cd "$BUILD"
ctest --output-on-failure -j"$(nproc)" "$@"
