#!/usr/bin/env bash
# The hand-block case on the default meshes and on meshes refined by 0.7x in element size (the
# hand's surface and cell sizes and the block's element size: with the block's mesh unchanged the
# late contact area kept growing, 1,018 -> 1,414 mm^2 at 5 ms): contact force, area and the 25 mm^2 peak
# pressure at each output, side by side, with the differences the contact issue asks for (force
# and area within 10 %, 25 mm^2 peak within 15 %), the same for the windowed force and area, and
# each run's contact impulse over the whole run (the time integral of the normal force).
#   bench/hand_block_mesh_study.sh [--scenario FILE] [--levels 2|3] [--ensemble N] [--smooth-boundaries SIGMA]
#                                  [--pressure-window TAU] [labels.h5]
#     labels.h5    default: the demo's out/pipeline/segment/labels.h5
#     --scenario   default: pipeline/scenarios/hand_block.toml. With rigid bones the study is
#                  cheaper (pipeline/scenarios/hand_block_rigid.toml), and a copy with
#                  `formulation = "standard"` or `pressure_smoothing = 0` compares the soft-tissue tets.
#     --levels 3   also a mesh refined by 0.49x (about 150k tets).
#     --ensemble N N runs per mesh, the first as given, the others with the bodies' initial
#                  velocities scaled by 1 + k 1e-6 (k = 1 .. N-1): a change of the input far below
#                  anything physical, so the spread of the results over the N runs is how much the
#                  impact amplifies a last-bit difference (the step's, the summation order's). Prints
#                  each figure's mean and spread per mesh and the meshes' difference of means beside
#                  the spread: a difference between meshes below the spread cannot be told from it.
#     --smooth-boundaries SIGMA  the hand meshed with tactus-mesh --smooth-boundaries SIGMA (voxels):
#                  boundaries on Gaussian-smoothed label indicators instead of the voxels' staircase.
#     --pressure-window TAU  the scenario's contact_solver.pressure_window set to TAU seconds: the reported
#                  pressure (and with it the 25 mm^2 peak) and the windowed force and area become
#                  exponential averages over TAU, like a sensor of that time constant (e.g. 2.5e-4, the
#                  bandwidth of the +-0.25 ms force and area; the default 1e-5 passes the ringing).
# Environment: TACTUS_BUILD_DIR (default build/), WORK (default a temporary folder). On 2 cores
# about 3 min for two levels of the rigid-bone case, 5 min with deformable bones (smoothed ANP);
# the third level takes 5-10 min with rigid bones, 9 min with deformable ones.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
B=${TACTUS_BUILD_DIR:-$ROOT/build}
SCENARIO=$ROOT/pipeline/scenarios/hand_block.toml
LEVELS=2
ENSEMBLE=1
SMOOTH=()
WINDOW=
LABELS=$ROOT/out/pipeline/segment/labels.h5
while [ $# -gt 0 ]; do
  case "$1" in
    --scenario) SCENARIO=$(cd "$(dirname "$2")" && pwd)/$(basename "$2"); shift 2 ;;
    --levels) LEVELS=$2; shift 2 ;;
    --ensemble) ENSEMBLE=$2; shift 2 ;;
    --smooth-boundaries) SMOOTH=(--smooth-boundaries "$2"); shift 2 ;;
    --pressure-window) WINDOW=$2; shift 2 ;;
    -*) echo "usage: bench/hand_block_mesh_study.sh [--scenario FILE] [--levels 2|3] [--ensemble N] [--smooth-boundaries SIGMA] [--pressure-window TAU] [labels.h5]" >&2; exit 2 ;;
    *) LABELS=$1; shift ;;
  esac
done
[ "$LEVELS" = 2 ] || [ "$LEVELS" = 3 ] || { echo "--levels: 2 or 3" >&2; exit 2; }
[[ "$ENSEMBLE" =~ ^[1-9]$ ]] || { echo "--ensemble: 1 to 9 runs per mesh" >&2; exit 2; }
[ -f "$SCENARIO" ] || { echo "no scenario $SCENARIO" >&2; exit 2; }
[ -f "$LABELS" ] || { echo "no $LABELS: run scripts/demo.sh first, or pass a labels.h5" >&2; exit 2; }
W=${WORK:-$(mktemp -d)}
[ -z "${WORK:-}" ] && trap 'rm -rf "$W"' EXIT
if [ -n "$WINDOW" ]; then
  # The scenario with its pressure window replaced (mesh paths resolve from --meshes, so the copy
  # may live in the work folder).
  /usr/bin/python3 - "$SCENARIO" "$W/scenario_window.toml" "$WINDOW" <<'PY'
import re, sys
text, tau = open(sys.argv[1]).read(), sys.argv[3]
try:
    if not float(tau) > 0:
        raise ValueError
except ValueError:
    sys.exit(f"--pressure-window: a time > 0 in seconds, not {tau!r}")
if re.search(r"^\s*pressure_window\s*=", text, flags=re.M):
    sys.exit(f"{sys.argv[1]} sets pressure_window itself: edit it there instead of --pressure-window")
if re.search(r"^\s*\[contact_solver\]", text, flags=re.M):
    text = re.sub(r"^(\s*\[contact_solver\][^\n]*\n)", lambda m: m.group(1) + f"pressure_window = {tau}\n", text, count=1, flags=re.M)
else:
    text += f"\n[contact_solver]\npressure_window = {tau}\n"
open(sys.argv[2], "w").write(text)
PY
  SCENARIO=$W/scenario_window.toml
fi
names=(default fine)
[ "$LEVELS" = 3 ] && names+=(finer)
for name in "${names[@]}"; do
  if [ -e "$W/$name" ]; then  # only a folder this script made is replaced
    [ -f "$W/$name/.tactus_mesh_study" ] || { echo "$W/$name exists and was not made by this script; not replaced" >&2; exit 2; }
    rm -rf "${W:?}/$name"
  fi
  mkdir -p "$W/$name/mesh" "$W/$name/object" && touch "$W/$name/.tactus_mesh_study"
  case $name in
    default) sizes=() block=0.008 ;;
    fine) sizes=(--facet-size 2.8 --bone-facet-size 2.1 --cell-size 4.9 --bone-cell-size 2.45 --facet-distance 0.42) block=0.0056 ;;
    finer) sizes=(--facet-size 1.96 --bone-facet-size 1.47 --cell-size 3.43 --bone-cell-size 1.715 --facet-distance 0.294) block=0.00392 ;;
  esac
  "$B/mesher/tactus-mesh" "$LABELS" "${sizes[@]}" "${SMOOTH[@]}" -o "$W/$name/mesh/mesh.msh" -q
  "$B/mesher/tactus-mesh" fibres "$W/$name/mesh/mesh.msh" --angle 30 --axis z -o "$W/$name/mesh/fibres.vtu" -q
  "$B/mesher/tactus-mesh" box --size 0.04 0.08 0.16 --origin 0 -0.06 0.04 --element-size "$block" -o "$W/$name/object/block.msh" -q
  echo "== $name mesh: solving $(basename "$SCENARIO")"
  "$B/solver/tactus-solve" "$SCENARIO" --meshes "$W/$name" -o "$W/$name/out" -q
  for ((k = 1; k < ENSEMBLE; k++)); do
    # The same scenario with every initial_velocity scaled by 1 + k 1e-6 (mesh paths resolve from --meshes).
    /usr/bin/python3 - "$SCENARIO" "$W/$name/scenario_$k.toml" "$k" <<'PY'
import re, sys
text, k = open(sys.argv[1]).read(), int(sys.argv[3])
def scaled(m):
    values = [float(v) * (1 + k * 1e-6) for v in m.group(2).split(",")]
    return m.group(1) + ", ".join(repr(v) for v in values) + "]"
text, n = re.subn(r"^(\s*initial_velocity\s*=\s*\[)([^\]]*)\]", scaled, text, flags=re.M)
if n == 0:
    sys.exit(f"{sys.argv[1]}: no initial_velocity to perturb for --ensemble")
open(sys.argv[2], "w").write(text)
PY
    echo "== $name mesh: ensemble run $((k + 1)) of $ENSEMBLE (initial velocities x (1 + $k e-6))"
    "$B/solver/tactus-solve" "$W/$name/scenario_$k.toml" --meshes "$W/$name" -o "$W/$name/out_$k" -q
  done
done
/usr/bin/python3 - "$ROOT/bench" "$W" "$ENSEMBLE" "${names[@]}" <<'PY'
import json, sys
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, sys.argv[1])
from history_kit import centred_mean, read_columns, time_integral
w, ensemble, names = sys.argv[2], int(sys.argv[3]), sys.argv[4:]
runs = {n: json.load(open(f"{w}/{n}/out/run.json")) for n in names}
# Each history read once (the 0.49x run's is ~150 MB): time, normal force, area.
histories = {n: read_columns(f"{w}/{n}/out/history.csv", "contact_normal_force", "contact_area") for n in names}
def impulse(n):
    t, force, _ = histories[n]
    return time_integral(t, force)
for n, j in runs.items():
    print(f"{n}: {j['tets']} tets, {j['contact']['pairs'][0]['slave_nodes']} skin nodes, {j['steps']} steps, {j['wall_time_s']:.0f} s, "
          f"contact impulse {impulse(n):.3f} N s")
def rel(x, y):
    return f"{100 * (y / x - 1):+.1f} %" if x else "-"
for a_name, b_name in zip(names, names[1:]):
    d, f = runs[a_name], runs[b_name]
    print(f"\n{a_name} / {b_name}:")
    print("| t (ms) | force (N) | diff | windowed force (N) | diff | area (mm^2) | diff | windowed area (mm^2) | diff | 25 mm^2 peak (MPa) | diff |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for a, b in zip(d["contact"]["at_outputs"], f["contact"]["at_outputs"]):
        cells = [f"{a['time'] * 1e3:.0f}"]
        for key, scale, digits in (("normal_force", 1, 0), ("windowed_normal_force", 1, 0), ("area", 1e6, 0), ("windowed_area", 1e6, 0),
                                   ("averaged_peak_pressure", 1e-6, 2)):
            cells += [f"{scale * a[key]:.{digits}f} / {scale * b[key]:.{digits}f}", rel(a[key], b[key])]
        print("| " + " | ".join(cells) + " |")
# Where each mesh's 25 mm^2 peak sits (current coordinates, run.json's averaged_at) and how far apart
# the meshes' sites are: a peak that moves between meshes is a different contact, not a converging one.
print("\nwhere the 25 mm^2 peak is (current position, mm), " + " / ".join(names) + ", and the distance between sites:")
print("| t (ms) | " + " | ".join(names) + " | distances (mm) |")
print("|---|" + "---|" * len(names) + "---|")
for i, o in enumerate(runs[names[0]]["contact"]["at_outputs"]):
    sites = [runs[n]["contact"]["at_outputs"][i]["averaged_at"] for n in names]
    gaps = [sum((1e3 * (p - q)) ** 2 for p, q in zip(a, b)) ** 0.5 for a, b in zip(sites, sites[1:])]
    print(f"| {o['time'] * 1e3:.0f} | " + " | ".join("(" + ", ".join(f"{1e3 * c:.1f}" for c in s) + ")" for s in sites) + " | " +
          ", ".join(f"{g:.1f}" for g in gaps) + " |")
# The 25 mm^2 average at the same material points on every mesh: the finest mesh's three highest
# sites (at least 10 mm apart), each taken on the other meshes about the skin node nearest to it
# in the reference configuration (bench/pressure_sites.py, the solver's average recomputed from the
# state files). The largest average above is a maximum over sites; this compares the field.
from pressure_sites import Field, state_files
files = {n: state_files(f"{w}/{n}/out") for n in names}
print("\n25 mm^2 averages (MPa) at the " + names[-1] + " mesh's three highest sites, on each mesh (" + " / ".join(names) + "):")
print("| t (ms) | site (x, y, z at " + names[-1] + ", mm) | " + " / ".join(names) + " | diffs |")
print("|---|---|---|---|")
for o in runs[names[0]]["contact"]["at_outputs"]:
    t = round(o["time"], 9)
    if any(t not in files[n] for n in names):
        continue
    fields = {n: Field(files[n][t]) for n in names}
    finest = fields[names[-1]]
    for node, _ in finest.sites():
        X = finest.state["X"][node]
        values = [fields[n].at_material_point(X)[0] * 1e-6 for n in names]
        site = ", ".join(f"{1e3 * c:.0f}" for c in finest.state["x"][node])
        print(f"| {t * 1e3:.0f} | ({site}) | " + " / ".join(f"{v:.2f}" for v in values) + " | " + ", ".join(rel(a, b) for a, b in zip(values, values[1:])) + " |")
# The same at a lower bandwidth: force and area averaged over +-0.25 ms about each output. The
# windowed values above average over the pressure window (10 us by default), which passes the
# block's and the bones' ringing (tens of kHz) that differs from mesh to mesh.
times = [o["time"] for o in runs[names[0]]["contact"]["at_outputs"]]
low = {n: (centred_mean(histories[n][0], histories[n][1], times, 2.5e-4), centred_mean(histories[n][0], histories[n][2], times, 2.5e-4))
       for n in names}
print("\nforce and area averaged over +-0.25 ms about each output, " + " / ".join(names) + ":")
print("| t (ms) | force (N) | diffs | area (mm^2) | diffs |")
print("|---|---|---|---|---|")
for i, t in enumerate(times):
    force = [low[n][0][i] for n in names]
    area = [low[n][1][i] * 1e6 for n in names]
    print(f"| {t * 1e3:.0f} | " + " / ".join(f"{x:.0f}" for x in force) + " | " + ", ".join(rel(x, y) for x, y in zip(force, force[1:])) +
          " | " + " / ".join(f"{x:.0f}" for x in area) + " | " + ", ".join(rel(x, y) for x, y in zip(area, area[1:])) + " |")
if ensemble > 1:
    # Each figure per member of each mesh's ensemble: +-0.25 ms force and area, windowed force and
    # area, 25 mm^2 peak; its mean and spread (max - min) per mesh, then the difference of the
    # meshes' means beside the larger of their spreads (both relative to the first mesh's mean).
    # The first member is the run above (its history and run.json already read); each file once.
    def members(n):
        yield runs[n], histories[n]
        for k in range(1, ensemble):
            d = f"{w}/{n}/out_{k}"
            yield json.load(open(f"{d}/run.json")), read_columns(f"{d}/history.csv", "contact_normal_force", "contact_area")
    figures = {}
    for n in names:
        rows = []
        for run, (t, force, area) in members(n):
            fl, al = centred_mean(t, force, times, 2.5e-4), centred_mean(t, area, times, 2.5e-4)
            rows.append([(fl[i], 1e6 * al[i], o["windowed_normal_force"], 1e6 * o["windowed_area"], 1e-6 * o["averaged_peak_pressure"])
                         for i, o in enumerate(run["contact"]["at_outputs"])])
            print(f"{n} member {len(rows)}: {run['steps']} steps, contact impulse {time_integral(t, force):.4f} N s")
        figures[n] = rows
    labels = ("force +-0.25 ms (N)", "area +-0.25 ms (mm^2)", "windowed force (N)", "windowed area (mm^2)", "25 mm^2 peak (MPa)")
    print(f"\nensembles of {ensemble} runs per mesh (initial velocities x (1 + k 1e-6)): mean [min, max] per mesh; "
          "between meshes the difference of means and the larger ensemble spread, both relative to the first mesh's mean")
    for q, label in enumerate(labels):
        print(f"\n{label}:")
        print("| t (ms) | " + " | ".join(names) + " | " + " | ".join(f"{a} / {b}: diff, spread" for a, b in zip(names, names[1:])) + " |")
        print("|---|" + "---|" * (2 * len(names) - 1))
        for i, t in enumerate(times):
            stats = []
            for n in names:
                v = [rows[i][q] for rows in figures[n]]
                stats.append((sum(v) / len(v), min(v), max(v)))
            cells = [f"{1e3 * t:.0f}"] + [f"{m:.3g} [{lo:.3g}, {hi:.3g}]" for m, lo, hi in stats]
            for (ma, la, ha), (mb, lb, hb) in zip(stats, stats[1:]):
                cells.append(f"{100 * (mb / ma - 1):+.1f} %, {100 * max(ha - la, hb - lb) / ma:.1f} %" if ma else "-")
            print("| " + " | ".join(cells) + " |")
PY
