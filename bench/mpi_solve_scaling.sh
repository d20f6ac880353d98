#!/usr/bin/env bash
# Whole runs of tactus-solve over MPI ranks against OpenMP threads on this machine (issue: MPI,
# "Performance"; docs/studies/mpi-scaling.md): 1 x 1, 1 rank x 2 threads and 2 ranks x 1 thread,
# interleaved ROUNDS times, on two cases:
#   cube   the benchmark cube (bench/cases/cube.toml, 48,000 neo-Hookean tets, no contact), 0.05 s;
#   hand   the hand-block case on its pinned meshes (bench/references): 69,739 tets, ANP hgo skin,
#          linear elastic bones, mortar contact with friction, the nodal step bound; 0.3 ms;
#   box    the cube's scenario on the throughput bench's 1M-tet box (55^3 cells, 998,250 tets),
#          0.03 s (301 steps; about 4 minutes for 5 rounds): CASES="box" (default "cube hand").
# Per layout: the median over rounds of run.json's wall time (the whole run, outputs included), of
# the stress passes' and of contact's (the slowest rank's, on ranks), the steps, and the peak
# resident memory of each process (of the first round). The results are compared bit for bit
# against the 1 x 1 run (history.csv and the last state). Last, the data structures' bytes of one
# process and of each rank (run.json memory_bytes) against the issue's per-rank memory bound.
#   bench/mpi_solve_scaling.sh [ROUNDS]      (default 5; TACTUS_BUILD_DIR: default build/)
# Never time it while something else runs.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
B=${TACTUS_BUILD_DIR:-$ROOT/build}
ROUNDS=${1:-5}
S=$B/solver/tactus-solve
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl_vader_single_copy_mechanism=none
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
"$B/data_samples/tactus-sample-mesh" --size 0.1 0.1 0.1 --cells 20 20 20 -o "$W/cube.msh" -q
CASES=${CASES:-cube hand}
[[ " $CASES " == *" hand "* ]] && TACTUS_BUILD_DIR=$B bash "$ROOT/bench/references/hand_block_meshes.sh" "$W/hand" > /dev/null
[[ " $CASES " == *" box "* ]] && mkdir -p "$W/box" && "$B/data_samples/tactus-sample-mesh" --size 0.1 0.1 0.1 --cells 55 55 55 -o "$W/box/cube.msh" -q
run() {  # run CASE LAYOUT ROUND
  local name=$1 layout=$2 round=$3 out="$W/$1.$2.$3" args
  if [ "$name" = cube ]; then
    args=("$ROOT/bench/cases/cube.toml" --meshes "$W" --end-time 0.05)
  elif [ "$name" = box ]; then
    args=("$ROOT/bench/cases/cube.toml" --meshes "$W/box" --end-time 0.03 --set run.checkpoint_wall_interval=0)
  else
    args=("$ROOT/pipeline/scenarios/hand_block.toml" --meshes "$W/hand" --end-time 0.3e-3 --set run.checkpoint_wall_interval=0)
  fi
  # The child's peak resident memory (kB) beside the output (on ranks run.json has each rank's).
  local peak=(/usr/bin/python3 -c "import resource, subprocess, sys; subprocess.run(sys.argv[2:], check=True)
open(sys.argv[1], 'w').write(str(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss))" "$W/$1.$2.$3.kB")
  case $layout in
    1x1) "${peak[@]}" "$S" "${args[@]}" -o "$out" -q --set run.threads=1 ;;
    1x2) "${peak[@]}" "$S" "${args[@]}" -o "$out" -q --set run.threads=2 ;;
    2x1) mpiexec -np 2 --bind-to core "$S" "${args[@]}" -o "$out" -q --set run.threads=1 ;;
  esac
}
for name in $CASES; do
  for round in $(seq "$ROUNDS"); do
    for layout in 1x1 1x2 2x1; do run "$name" "$layout" "$round"; done
  done
  /usr/bin/python3 - "$W" "$name" "$ROUNDS" <<'PY'
import filecmp, json, os, statistics, sys
work, name, rounds = sys.argv[1], sys.argv[2], int(sys.argv[3])
rows = {}
for layout in ("1x1", "1x2", "2x1"):
    wall, stress, contact = [], [], []
    for r in range(1, rounds + 1):
        j = json.load(open(f"{work}/{name}.{layout}.{r}/run.json"))
        wall.append(j["wall_time_s"])
        ranks = j.get("ranks")
        stress.append(max(x["stress_passes_s"] for x in ranks) if ranks else j["timing_s"]["stress_passes"])
        contact.append(max(x["contact_s"] for x in ranks) if ranks else j["timing_s"]["contact"])
    if ranks:
        memory = [x["peak_resident_bytes"] / 2**20 for x in json.load(open(f"{work}/{name}.{layout}.1/run.json"))["ranks"]]
    else:
        memory = [int(open(f"{work}/{name}.{layout}.1.kB").read()) / 1024]
    rows[layout] = (statistics.median(wall), statistics.median(stress), statistics.median(contact), j["steps"], ranks, memory)
base = f"{work}/{name}.1x1.1"
states = sorted(os.listdir(f"{base}/results"))
for layout in ("1x2", "2x1"):
    other = f"{work}/{name}.{layout}.1"
    same = filecmp.cmp(f"{base}/history.csv", f"{other}/history.csv", shallow=False) and filecmp.cmp(
        f"{base}/results/{states[-1]}", f"{other}/results/{states[-1]}", shallow=False)
    print(f"{name}: {layout} gives the 1 x 1 bits: {same}")
for layout, (wall, stress, contact, steps, ranks, memory) in rows.items():
    print(f"{name} {layout}: {steps} steps, run {wall:.2f} s, stress passes {stress:.2f} s, contact {contact:.2f} s, "
          f"{1e3 * wall / steps:.3f} ms per step; peak memory per process {', '.join(f'{m:.0f}' for m in memory)} MiB"
          + (f"; per rank (tets, halo doubles, ANP exchange doubles and messages, owned nodes whose forces it sends, nodes it integrates, ghost doubles per update, doubles it sends in the pass's gather, gather s, force packing s): "
             f"{[(x['tets'], x['halo_doubles_per_pass'], x['anp_exchange_doubles_per_pass'], x['anp_exchange_messages_per_pass'], x['owned_nodes'], x['integrated_nodes'], x['ghost_doubles_per_exchange'], round(x.get('gather_doubles_per_pass', -1)), round(x['sums_s'], 3), round(x['force_gather_s'], 3)) for x in ranks]}"
             if ranks else ""))
print(f"{name}: 2 ranks x 1 thread / 1 rank x 2 threads, whole run: {rows['2x1'][0] / rows['1x2'][0]:.3f}; "
      f"speed-up over 1 x 1: threads {rows['1x1'][0] / rows['1x2'][0]:.2f}, ranks {rows['1x1'][0] / rows['2x1'][0]:.2f}")
# The data structures' bytes (run.json memory_bytes: the model, the integrator with its stress pass)
# against the issue's bound: 1.1 x the one process's bytes per tet x the rank's tets (before its halo).
one = json.load(open(f"{work}/{name}.1x1.1/run.json"))
per_tet = (one["memory_bytes"]["model"] + one["memory_bytes"]["solver"]) / one["tets"]
print(f"{name}: one process holds {one['memory_bytes']['model'] / 2**20:.1f} MiB of model and {one['memory_bytes']['solver'] / 2**20:.1f} MiB "
      f"of solver ({per_tet:.1f} bytes per tet); per rank (model, solver, the bound before the halo, MiB): "
      + ", ".join(f"({x['model_bytes'] / 2**20:.1f}, {x['solver_bytes'] / 2**20:.1f}, {1.1 * per_tet * x['tets'] / 2**20:.1f})"
                  for x in json.load(open(f"{work}/{name}.2x1.1/run.json"))["ranks"]))
PY
done
