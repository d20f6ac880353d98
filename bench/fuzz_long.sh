#!/usr/bin/env bash
# The long fuzz budget: 2,000 deterministic mutations per reader of user files (scenario, .msh
# ASCII and binary, stack.json, PNG slice, labels.h5, run.json, history.csv, .vtu), each read in a
# child process with a time and memory limit. Failing inputs are saved to bench/fuzz-found/ (copy
# them into tests/fuzz/regressions/<reader>/ to keep them as regression tests).
#   bench/fuzz_long.sh [mutations per reader, default 2000] [seed, default 7]
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
B=${TACTUS_BUILD_DIR:-$ROOT/build}
time "$B/tests/fuzz/tactus-fuzz" --mutations "${1:-2000}" --seed "${2:-7}" --save "$ROOT/bench/fuzz-found"
