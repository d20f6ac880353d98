#!/usr/bin/env bash
# The stress pass over MPI ranks against OpenMP threads on this machine (issue: MPI,
# "Performance"): 2 ranks x 1 thread against 1 rank x 2 threads, interleaved ROUNDS times, on the
# 1M-tet throughput box (6 x 55^3 tets) and on the hand of the hand-block case (the pinned 70k-tet
# mesh of bench/references); then the halo per rank at 4 and 8 ranks (oversubscribed: their times
# mean nothing here, their halo and record bytes do). Each line of tactus-bench-mpi gives the
# median of its passes; this script prints the medians of those medians and their ratio.
# All tets run as neo-Hookean standard tets (tactus-bench-mpi --formulation anp runs them as ANP tets).
#   bench/mpi_scaling.sh [ROUNDS]      (default 5; TACTUS_BUILD_DIR: default build/)
# Open MPI binds each of up to 2 ranks to one core: the 1 x 2 run is started with --bind-to none,
# or its two threads would share one core. Never time it while something else runs.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
B=${TACTUS_BUILD_DIR:-$ROOT/build}
ROUNDS=${1:-5}
BENCH=$B/bench/tactus-bench-mpi
[ -x "$BENCH" ] || { echo "mpi_scaling: $BENCH not built (configure with -DTACTUS_MPI=ON and MPI installed)" >&2; exit 1; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl_vader_single_copy_mechanism=none
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
TACTUS_BUILD_DIR=$B bash "$ROOT/bench/references/hand_block_meshes.sh" "$W" > /dev/null
for case in "box --cells 55" "hand --mesh $W/mesh/mesh.msh"; do
  name=${case%% *}
  args=${case#* }
  for round in $(seq "$ROUNDS"); do
    # shellcheck disable=SC2086
    mpiexec -np 1 --bind-to none "$BENCH" $args --threads 2 --rounds 31 > "$W/$name.1x2.$round"
    # shellcheck disable=SC2086
    mpiexec -np 2 --bind-to core "$BENCH" $args --threads 1 --rounds 31 > "$W/$name.2x1.$round"
  done
  cat "$W/$name.1x2.1" "$W/$name.2x1.1"
  for np in 4 8; do
    # shellcheck disable=SC2086
    mpiexec -np "$np" --oversubscribe "$BENCH" $args --threads 1 --rounds 1 > "$W/$name.$np"
    sed "s/stress pass median.*/(oversubscribed: times not meaningful)/" "$W/$name.$np"
  done
  /usr/bin/python3 - "$W" "$name" "$ROUNDS" <<'PY'
import re, statistics, sys
work, name, rounds = sys.argv[1], sys.argv[2], int(sys.argv[3])
def medians(layout):
    out = []
    for r in range(1, rounds + 1):
        text = open(f"{work}/{name}.{layout}.{r}").read()
        out.append(float(re.search(r"stress pass median ([0-9.]+) ms", text).group(1)))
    return out
omp, mpi = medians("1x2"), medians("2x1")
print(f"{name}: 1 rank x 2 threads {statistics.median(omp):.3f} ms (rounds {', '.join(f'{x:.2f}' for x in omp)}); "
      f"2 ranks x 1 thread {statistics.median(mpi):.3f} ms (rounds {', '.join(f'{x:.2f}' for x in mpi)}); "
      f"MPI / OpenMP {statistics.median(mpi) / statistics.median(omp):.3f}")
PY
done
# The model past this machine (docs/design.md, "The stress pass over MPI ranks"): a 5M-tet hand
# on 8 / 32 / 128 ranks of one thread each, from the hand's measured per-tet cost (2 ranks x 1
# thread) and its halo at 8 ranks, scaled as a surface, (tets per rank)^(2/3); the network 10 Gb/s
# with 5 us per message. Per step and rank: the stress pass, the halo (no overlap counted: an upper
# bound), the minima's MINLOC (2 log2 P latencies), and the per-atom sums as gathered today
# (every atom's record to every rank, a ring: (P-1)/P of them through each rank's link).
/usr/bin/python3 - "$W" <<'PY'
import math, re, sys
work = sys.argv[1]
def grab(path, pattern, cast=float):
    return [cast(x) for x in re.search(pattern, open(path).read()).group(1).split()]
tets = grab(f"{work}/hand.2x1.1", r"x threads 1: (\d+) tets", int)[0]
per_tet = []
for r in range(1, 100):
    try:
        per_tet.append(grab(f"{work}/hand.2x1.{r}", r"stress pass median ([0-9.]+) ms")[0] * 1e-3 * 2 / tets)
    except OSError:
        break
t_tet = sorted(per_tet)[len(per_tet) // 2]
halo8 = max(grab(f"{work}/hand.8", r"halo doubles sent per rank per pass: ([0-9 ]+)\n", int))
msgs8 = max(grab(f"{work}/hand.8", r"halo messages sent per rank per pass: ([0-9 ]+)\n", int))
atoms = grab(f"{work}/hand.8", r"tets, (\d+) atoms", int)[0]
record = grab(f"{work}/hand.8", r"MPI_Allgatherv\): (\d+) bytes", int)[0] / atoms
c = halo8 / (tets / 8) ** (2 / 3)
N, bandwidth, latency = 5e6, 10e9 / 8, 5e-6
print(f"model: per-tet cost {t_tet * 1e9:.1f} ns (hand, 2 ranks x 1 thread); halo at 8 ranks {halo8} doubles, {msgs8} messages per rank "
      f"(c = {c:.2f} doubles per (tets per rank)^(2/3)); records {record:.0f} bytes per atom of 128 tets; 10 Gb/s, 5 us per message")
print("| ranks | tets per rank | stress pass (ms) | halo per rank (kB) | halo time (ms) | minima MINLOC (ms) | records gathered (ms) | efficiency, records each step | efficiency, records at history rows only |")
print("|---|---|---|---|---|---|---|---|---|")
for P in (8, 32, 128):
    n = N / P
    compute = n * t_tet
    halo_bytes = 8 * c * n ** (2 / 3)
    halo = msgs8 * latency + halo_bytes / bandwidth
    minloc = 2 * math.log2(P) * latency
    records = (P - 1) / P * (N / 128) * record / bandwidth + math.log2(P) * latency
    serial = N * t_tet
    e_now = serial / (P * (compute + halo + minloc + records))
    e_next = serial / (P * (compute + halo + minloc))
    print(f"| {P} | {n:,.0f} | {compute * 1e3:.2f} | {halo_bytes / 1e3:.0f} | {halo * 1e3:.3f} | {minloc * 1e3:.3f} | {records * 1e3:.2f} | "
          f"{100 * e_now:.0f} % | {100 * e_next:.0f} % |")
PY
