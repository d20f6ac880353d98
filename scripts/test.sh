#!/usr/bin/env bash
# Sets up (see setup.sh) and runs the whole test suite through CTest.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD=${TACTUS_BUILD_DIR:-$ROOT/build}
bash "$ROOT/scripts/setup.sh"
cd "$BUILD"
# Tests run in parallel on few cores: OpenMP workers spinning at barriers would steal the cores of
# the other tests (a 4 s test took 60 s), so idle workers sleep instead.
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}
ctest --output-on-failure -j"$(nproc)" "$@"
