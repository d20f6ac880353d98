#!/usr/bin/env bash
# The hand-block case with deformable bones and block (hand_block.toml) and with rigid ones
# (hand_block_rigid.toml), on the meshes pinned with the solver reference
# (bench/references/hand_block_*.msh.xz): steps, wall time and its split, and at each output the
# contact force, area and 25 mm^2 peak pressure of the rigid run against the deformable one (the
# rigid-bodies issue asks for 5 %, 5 % and 10 %).
#   bench/hand_block_rigid.sh
# Environment: TACTUS_BUILD_DIR (default build/), WORK (default a temporary folder). About 75 s on
# 2 cores; never time it while something else runs.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
B=${TACTUS_BUILD_DIR:-$ROOT/build}
W=${WORK:-$(mktemp -d)}
[ -z "${WORK:-}" ] && trap 'rm -rf "$W"' EXIT
TACTUS_BUILD_DIR=$B bash "$ROOT/bench/references/hand_block_meshes.sh" "$W"
for case in hand_block hand_block_rigid; do
  echo "== $case"
  "$B/solver/tactus-solve" "$ROOT/pipeline/scenarios/$case.toml" --meshes "$W" -o "$W/$case.out" -q --force
done
/usr/bin/python3 - "$W" <<'PY'
import json, sys
w = sys.argv[1]
runs = {c: json.load(open(f"{w}/{c}.out/run.json")) for c in ("hand_block", "hand_block_rigid")}
for c, j in runs.items():
    t = j["timing_s"]
    added = j.get("mass_scaling", {}).get("bodies", {}).get("hand", {}).get("fraction", 0.0)
    print(f"{c:17s} {j['steps']:6d} steps, dt {j['time_step']['min']:.3g}..{j['time_step']['max']:.3g} s, wall {j['wall_time_s']:.1f} s "
          f"(stress {t['stress_passes']:.1f}, contact {t['contact']:.1f}, rest {t['rest']:.1f}); mass added to the hand {100 * added:.2f} %")
d, r = (runs[c]["contact"]["at_outputs"] for c in ("hand_block", "hand_block_rigid"))
print("t (ms)   force N: deformable  rigid  diff   |  area mm^2: deformable  rigid  diff   |  25 mm^2 peak MPa: deformable  rigid  diff")
for a, b in zip(d, r):
    pct = lambda x, y: 100 * (y / x - 1) if x else float("nan")
    print(f"{1e3 * a['time']:5.1f}   {a['normal_force']:10.1f} {b['normal_force']:8.1f} {pct(a['normal_force'], b['normal_force']):+6.1f} %"
          f"  |  {1e6 * a['area']:10.1f} {1e6 * b['area']:8.1f} {pct(a['area'], b['area']):+6.1f} %"
          f"  |  {a['averaged_peak_pressure'] / 1e6:10.3f} {b['averaged_peak_pressure'] / 1e6:8.3f} "
          f"{pct(a['averaged_peak_pressure'], b['averaged_peak_pressure']):+6.1f} %")
PY
