#!/usr/bin/env bash
# Shared cores (docs/studies/shared-cores.md): the stress passes of the cube (bench/cases/cube.toml,
# 48,000 tets, 2,000 steps, no contact) and the contact of the hand-block case (its pinned meshes,
# the first 0.5 ms) on run.threads = 1, 2 (fixed) and 0 (automatic: ThreadTuner), each with and
# without a CPU-bound neighbour (`yes > /dev/null`), OMP_WAIT_POLICY=PASSIVE (what tactus-pipeline
# and scripts/test.sh set); ROUNDS rounds (default 5), every configuration once per round,
# interleaved. Prints one line per run and the medians (timing_s of run.json). About 12 minutes
# on 2 cores; never time it while something else runs.
#   bench/shared_cores.sh
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
B=${TACTUS_BUILD_DIR:-$ROOT/build}
ROUNDS=${ROUNDS:-5}
W=${WORK:-$(mktemp -d)}
[ -z "${WORK:-}" ] && trap 'rm -rf "$W"' EXIT
export OMP_WAIT_POLICY=PASSIVE
"$B/data_samples/tactus-sample-mesh" --size 0.1 0.1 0.1 --cells 20 20 20 -o "$W/cube.msh" -q
TACTUS_BUILD_DIR=$B bash "$ROOT/bench/references/hand_block_meshes.sh" "$W/hb" > /dev/null
for t in 0 1 2; do
  sed "s/^\[run\]/[run]\nthreads = $t/" "$ROOT/bench/cases/cube.toml" > "$W/cube_t$t.toml"
  sed "s/^\[run\]/[run]\nthreads = $t/" "$ROOT/pipeline/scenarios/hand_block.toml" > "$W/hb/hb_t$t.toml"
done
: > "$W/times.txt"
for round in $(seq "$ROUNDS"); do
  for neighbour in none busy; do
    hog=
    if [ "$neighbour" = busy ]; then
      yes > /dev/null &
      hog=$!
    fi
    for t in 1 2 0; do
      rm -rf "$W/o"
      "$B/solver/tactus-solve" "$W/cube_t$t.toml" --meshes "$W" -o "$W/o" -q
      stress=$(/usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['timing_s']['stress_passes'])" "$W/o/run.json")
      rm -rf "$W/o"
      "$B/solver/tactus-solve" "$W/hb/hb_t$t.toml" --meshes "$W/hb" -o "$W/o" -q --end-time 0.5e-3
      contact=$(/usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['timing_s']['contact'])" "$W/o/run.json")
      echo "round $round neighbour $neighbour threads $t cube_stress_s $stress hand_block_contact_s $contact" | tee -a "$W/times.txt"
    done
    [ -n "$hog" ] && kill "$hog" && wait "$hog" 2> /dev/null || true
  done
done
/usr/bin/python3 - "$W/times.txt" <<'PY'
import statistics
import sys
from collections import defaultdict

runs = defaultdict(lambda: ([], []))
for line in open(sys.argv[1]):
    f = line.split()
    key = (f[3], f[5])
    runs[key][0].append(float(f[7]))
    runs[key][1].append(float(f[9]))
print("neighbour threads   cube stress median (s)   hand-block contact median (s)")
for neighbour in ("none", "busy"):
    one = runs[(neighbour, "1")]
    for t in ("1", "2", "0"):
        s, c = runs[(neighbour, t)]
        label = {"1": "1", "2": "2 fixed", "0": "automatic"}[t]
        ms, mc = statistics.median(s), statistics.median(c)
        print(
            f"{neighbour:9} {label:9} {ms:8.2f} ({min(s):.2f}-{max(s):.2f}) x{ms / statistics.median(one[0]):.2f}"
            f"   {mc:8.2f} ({min(c):.2f}-{max(c):.2f}) x{mc / statistics.median(one[1]):.2f}"
        )
PY
