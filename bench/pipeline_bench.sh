#!/usr/bin/env bash
# Whole-pipeline benchmark on the default phantom (0.7 mm, the README's main job): every stage
# forced to run, its wall time and peak memory (from the kernel's rusage of each stage) printed
# from pipeline.json. Target on 2 cores: the whole pipeline <= 5 minutes.
# Usage: bench/pipeline_bench.sh [work folder, default out/bench/pipeline]
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD=${TACTUS_BUILD_DIR:-$ROOT/build}
WORK=${1:-$ROOT/out/bench/pipeline}
mkdir -p "$WORK"
start=$(date +%s%N)
"$BUILD/data_samples/tactus-phantom" -q -o "$WORK/phantom"
phantom_s=$(( ($(date +%s%N) - start) / 1000000 ))e-3
TACTUS_BUILD_DIR=$BUILD /usr/bin/python3 "$ROOT/pipeline/tactus-pipeline" "$WORK/phantom" \
  "$ROOT/pipeline/scenarios/hand_block.toml" -o "$WORK/run" --force -q
/usr/bin/python3 - "$WORK/run/pipeline.json" "$phantom_s" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
print(f"\n{'stage':10s} {'wall (s)':>10s} {'peak memory (MB)':>18s}")
print(f"{'phantom':10s} {float(sys.argv[2]):10.1f} {'':>18s}")
for s in j["stages"]:
    print(f"{s['stage']:10s} {s['wall_s']:10.1f} {s['peak_memory_mb']:18.0f}")
total = sum(s["wall_s"] for s in j["stages"]) + float(sys.argv[2])
print(f"{'total':10s} {total:10.1f}   (target <= 300 s on 2 cores)")
PY
