#!/usr/bin/env bash
# ranks/solve: tactus-solve under mpirun gives the one-process run's bits (issue: MPI, "Tests").
# Oracle: the same binary without mpirun, byte for byte (results/*.vtu, results.pvd, history.csv;
# none of them holds a wall time). Cases: the restart test's pad (cli/restart.sh: a bone inclusion
# in ANP hgo tissue sliding on a neo-Hookean block through mortar contact with friction and onto a
# rigid wall, node to surface; mass scaling and mass damping on) on 1 to 4 ranks; a rigid cube
# dropped under gravity onto the block (the rigid body's 6-dof reduction; Rayleigh beta) on 2 and 3
# ranks; the pad without mass scaling (owned-node stepping: each rank integrates its own nodes) on 2
# to 4 ranks and through a checkpoint; a gel block relaxing under gravity (adaptive damping, the
# run stopping at equilibrium) on 2 and 3 ranks; the pad failing numerically (its last good state) on
# 2 and 3 ranks; the pad with its atoms dealt round-robin over 2 ranks by
# --partition (a cut through the
# contact patch); the pad killed at 3 ranks and continued at 2, and killed at 2 and continued in
# one process, from checkpoints of one part per rank. (Self-contact:
# ranks/self_contact_on_N_ranks.) Bad input: more ranks than tets / 8, mismatched binaries, a
# --check that fails on rank 0 alone after the run (exit 5 at once), and a rank killed mid-run (the
# others stop within 10 s, naming it, and nothing is published).
# Usage: solve.sh BUILD_DIR
set -u
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
B=$(cd "$1" && pwd)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail=0
bad() { echo "FAIL: $*"; fail=1; }
cd "$T" || exit 1
S="$B/solver/tactus-solve"
M="mpiexec --bind-to none"
source "$HERE/../cli/pad_case.sh"
mv s.toml pad.toml
"$B/data_samples/tactus-sample-mesh" --size 0.01 0.01 0.01 --origin 0.005 0.005 0.0002 --cells 3 3 3 -o cube.msh -q
"$B/data_samples/tactus-sample-mesh" --size 0.01 0.01 0.01 --cells 2 2 1 -o tiny.msh -q
{
  cat <<'TOML'
[run]
end_time = 1.5e-3
output_times = [0.5e-3, 1.0e-3]
history_every = 5
gravity = [0.0, 0.0, -9.81]
[damping]
beta = 1.0e-6
[[bodies]]
name = "cube"
mesh = "cube.msh"
materials = { "*" = "steel" }
initial_velocity = [0.3, 0.0, -1.5]
[[bodies]]
name = "block"
mesh = "block.msh"
materials = { "*" = "block" }
[materials.steel]
type = "rigid"
density = 7800.0
[[contact]]
slave_body = "block"
slave_surface = "zmax"
master_body = "cube"
master_surface = "zmin"
friction = 0.2
TOML
  sed -n '/^\[materials.block\]/,/^density/p; /^\[\[boundary\]\]/,/^type = "fixed"/p' pad.toml  # the pad's block, fixed below
} > drop.toml
same_as() {  # same_as ORACLE DIR WHAT
  local f n=0
  for f in history.csv results.pvd $(cd "$1" && ls results/*.vtu); do
    cmp -s "$1/$f" "$2/$f" || { bad "$3: $f differs from the one-process run"; return; }
    n=$((n + 1))
  done
  echo "$3: $n files the same bits as the one-process run"
}
figure() { python3 -c "import json,sys; j=json.load(open('$1/run.json')); print($2)"; }
same_on_ranks() {  # same_on_ranks TOML ORACLE NAME WHAT NP...: NAME_npN on NP ranks, each the oracle's bits
  local toml=$1 oracle=$2 name=$3 what=$4 np
  shift 4
  for np in "$@"; do
    $M -np "$np" "$S" "$toml" -o "${name}_np$np" -q || { bad "$what on $np ranks failed"; continue; }
    same_as "$oracle" "${name}_np$np" "$what on $np ranks"
  done
}

"$S" pad.toml -o pad1 -q || bad "the one-process pad run failed"
echo "pad: $(figure pad1 "j['steps']") steps, $(figure pad1 "j['contact']['steps_in_contact']") in contact, $(figure pad1 "round(100 * j['mass_scaling']['bodies']['pad']['fraction'], 2)") % mass added to the pad"
same_on_ranks pad.toml pad1 pad "pad" 1 2 3 4
echo "per rank (4 ranks): $(figure pad_np4 "[(r['tets'], r['halo_doubles_per_pass'], round(r['stress_passes_s'], 3)) for r in j['ranks']]")"

"$S" drop.toml -o drop1 -q || bad "the one-process drop failed"
echo "rigid cube drop: $(figure drop1 "j['steps']") steps, $(figure drop1 "j['contact']['steps_in_contact']") in contact"
same_on_ranks drop.toml drop1 drop "rigid cube drop" 2 3

# A run that fails (the pad at 5e-6 s, about four times its stable step: an energy blow-up at step
# 14) writes its last good state: every rank computes its own tets' cell records of that state and
# rank 0 writes them; the same bits and the same exit code (3) on 2 and 3 ranks.
blowup="--set run.force_time_step=true --set run.time_step=5e-6"
"$S" pad.toml -o blow1 -q $blowup 2>/dev/null
[ $? -eq 3 ] || bad "the one-process pad at 5e-6 s should fail numerically (exit 3)"
[ -e blow1/results/last_good_state.vtu ] || bad "the failed one-process run wrote no last good state"
for np in 2 3; do
  $M -np $np "$S" pad.toml -o blow_np$np -q $blowup >/dev/null 2>&1
  code=$?
  [ $code -eq 3 ] || bad "the pad at 5e-6 s on $np ranks: exit $code, not 3"
  same_as blow1 blow_np$np "the failed pad (last good state) on $np ranks"
done

# Owned-node stepping (every run over ranks): each rank integrates only its own nodes and the
# contact, supported and rigid ones, the nodes it reads arriving from their owners after each
# update. The pad above also gathers the nodes mass scaling raised; without mass scaling: the same
# bits on 2 to 4 ranks, and killed at 3 ranks and continued at 2.
sed 's/^minimum_time_step = .*/minimum_time_step = 0.0/' pad.toml > padn.toml
"$S" padn.toml -o padn1 -q || bad "the one-process pad without mass scaling failed"
echo "pad without mass scaling: $(figure padn1 "j['steps']") steps, $(figure padn1 "j['contact']['steps_in_contact']") in contact"
same_on_ranks padn.toml padn1 padn "pad without mass scaling, owned-node stepping," 2 3 4
integrated() { figure "$1" "sum(r['integrated_nodes'] for r in j['ranks'])"; }
echo "nodes integrated per rank, 3 ranks: $(figure padn_np3 "[(r['integrated_nodes'], r['ghost_doubles_per_exchange']) for r in j['ranks']]") of $(figure padn1 "j['nodes']")"
[ "$(integrated padn_np3)" -gt 0 ] || bad "the pad without mass scaling should step owned nodes"
[ "$(integrated pad_np3)" -gt 0 ] || bad "the pad with mass scaling should step owned nodes"
[ "$(integrated drop_np3)" -gt 0 ] || bad "the rigid cube drop should step owned nodes"
$M -np 3 env TACTUS_KILL_AT=step:400 "$S" padn.toml -o padn_cp -q >/dev/null 2>&1
$M -np 2 "$S" --restart padn_cp -q || bad "the restart at 2 ranks (owned-node stepping) failed"
same_as padn1 padn_cp "pad without mass scaling killed at 3 ranks, continued at 2"

# Dynamic relaxation: a gel block (19,200 tets, 3 chunks of the sums over dofs) sagging under
# gravity with adaptive damping stops once relaxed and writes that state: the state is gathered
# then, so it is the one-process file on 2 and 3 ranks.
"$B/data_samples/tactus-sample-mesh" --size 0.03 0.03 0.01 --cells 20 20 8 -o gel.msh -q
cat > sag.toml <<'TOML'
[run]
end_time = 0.5
output_times = [0.5]
gravity = [0.0, 0.0, -9.81]
[damping]
adaptive = true
residual_tolerance = 1.0e-3
residual_after = 0.0
[[bodies]]
name = "gel"
mesh = "gel.msh"
materials = { "*" = "gel" }
[materials.gel]
type = "neo_hookean"
mu = 2000.0
bulk = 40000.0
density = 1000.0
[[boundary]]
body = "gel"
group = "zmin"
type = "fixed"
TOML
"$S" sag.toml -o sag1 -q || bad "the one-process sagging gel failed"
echo "sagging gel: relaxed at t = $(figure sag1 "j['end_time']") s after $(figure sag1 "j['steps']") steps"
same_on_ranks sag.toml sag1 sag "sagging gel, relaxed," 2 3

# A cut placed on purpose: the pad's atoms dealt round-robin between 2 ranks.
"$S" decompose pad.toml --ranks 2 -o metis.json > /dev/null
python3 - <<'PY'
import json
d = json.load(open("metis.json"))
d["atom_rank"] = [a % 2 for a in range(len(d["atom_rank"]))]
json.dump(d, open("dealt.json", "w"))
PY
$M -np 2 "$S" pad.toml -o pad_dealt -q --partition dealt.json || bad "the pad with a round-robin partition failed"
same_as pad1 pad_dealt "pad, atoms dealt round-robin over 2 ranks"

# Killed at 3 ranks (rank 0 raises SIGKILL at step 400), continued at 2; killed at 2, continued
# by one process. Each checkpoint is one part per rank (each rank's own nodes) and a manifest.
parts_of() {  # parts_of DIR: the part files of the newest complete checkpoint its killed run left
  /usr/bin/python3 - "$1" <<'PY'
import glob, json, sys
manifests = sorted(glob.glob(sys.argv[1] + ".partial-*/checkpoints/checkpoint_*.json"))
print(" ".join(p["file"] for p in json.load(open(manifests[-1]))["parts"]) if manifests else "none")
PY
}
$M -np 3 env TACTUS_KILL_AT=step:400 "$S" pad.toml -o pad_cp -q >/dev/null 2>&1
[ -e pad_cp/run.json ] && bad "a killed run published its folder"
echo "checkpoint left by 3 ranks: $(parts_of pad_cp)"
[[ "$(parts_of pad_cp)" =~ part0of3.h5\ .*part1of3.h5\ .*part2of3.h5$ ]] || bad "3 ranks should write 3 parts: $(parts_of pad_cp)"
$M -np 2 "$S" --restart pad_cp -q || bad "the restart at 2 ranks failed"
same_as pad1 pad_cp "killed at 3 ranks, continued at 2"
$M -np 2 env TACTUS_KILL_AT=step:400 "$S" pad.toml -o pad_cp1 -q >/dev/null 2>&1
echo "checkpoint left by 2 ranks: $(parts_of pad_cp1)"
[[ "$(parts_of pad_cp1)" =~ part1of2.h5$ ]] || bad "2 ranks should write 2 parts: $(parts_of pad_cp1)"
"$S" --restart pad_cp1 -q || bad "the restart in one process failed"
same_as pad1 pad_cp1 "killed at 2 ranks, continued by one process"

# Refused: more ranks than tets / 8 (24 tets: at most 3).
printf '[run]\nend_time = 1e-4\n[[bodies]]\nname = "tiny"\nmesh = "tiny.msh"\nmaterials = { "*" = "block" }\n' > tiny.toml
sed -n '/^\[materials.block\]/,/^density/p' drop.toml >> tiny.toml
expect() {  # expect WHAT TEXT COMMAND...: fails with exit 1 and a message containing TEXT
  local what=$1 text=$2
  shift 2
  "$@" > out.txt 2>&1
  local rc=$?
  [ "$rc" = 1 ] || bad "$what: exit $rc, expected 1"
  grep -q -- "$text" out.txt || bad "$what: no '$text' in: $(head -3 out.txt)"
  [ "$(grep -c 'tactus-solve: error' out.txt)" = 1 ] || bad "$what: the message should be printed once: $(grep -c 'tactus-solve: error' out.txt) times"
  echo "$what: $(grep 'tactus-solve: error' out.txt | head -1)"
}
expect "4 ranks for 24 tets" "at most 3 ranks" $M -np 4 "$S" tiny.toml -o tiny4 -q
[ -e tiny4 ] && bad "a refused run left an output folder"

# Mismatched binaries: rank 1 runs a copy whose bytes differ (one byte appended).
cp "$S" other-solve && printf 'x' >> other-solve
expect "mismatched binaries" "rank 1's hashes to" $M -np 1 "$S" pad.toml -o mixed -q : -np 1 ./other-solve pad.toml -o mixed -q

# A failure of rank 0 alone after the run (--check beyond its tolerance): exit 5 at once, the other
# rank waiting for it rather than giving up after 10 s and ending the job.
"$S" drop.toml -o drop_ref -q --write-reference ref.json
python3 -c "import json; r = json.load(open('ref.json')); r['figures']['end_time']['value'] *= 2; json.dump(r, open('ref.json', 'w'))"
start=$(date +%s.%N)
$M -np 2 "$S" drop.toml -o drop_check -q --check ref.json > check.txt 2>&1
rc=$?
took=$(python3 -c "print(round($(date +%s.%N) - $start, 2))")
echo "--check beyond tolerance on 2 ranks: exit $rc after $took s"
[ "$rc" = 5 ] || bad "--check beyond tolerance under mpirun: exit $rc, expected 5: $(head -3 check.txt)"
python3 -c "import sys; sys.exit(0 if $took < 8 else 1)" || bad "--check beyond tolerance took $took s (the other rank gave up waiting?)"
grep -q MPI_ABORT check.txt && bad "--check beyond tolerance aborted the job: $(grep -m1 'stopped' check.txt)"

# A rank killed mid-run: the others stop within 10 s, naming it, and nothing is published.
$M -np 2 "$S" pad.toml -o dies -q --end-time 0.2 > dies.txt 2>&1 &
launcher=$!
victim=""
for _ in $(seq 100); do
  for p in $(pgrep -f "tactus-solve pad.toml -o dies"); do
    grep -qz '^OMPI_COMM_WORLD_RANK=1$' "/proc/$p/environ" 2>/dev/null && victim=$p
  done
  [ -n "$victim" ] && break
  sleep 0.1
done
if [ -z "$victim" ]; then
  bad "rank 1 of the run to kill was not found"
else
  sleep 1
  kill -9 "$victim"
  start=$(date +%s.%N)
  wait "$launcher"
  rc=$?
  took=$(python3 -c "print(round($(date +%s.%N) - $start, 2))")
  echo "rank 1 killed: mpiexec exit $rc after $took s: $(grep -m1 -i 'rank 1\|signal 9' dies.txt)"
  [ "$rc" != 0 ] || bad "a run whose rank died exited 0"
  python3 -c "import sys; sys.exit(0 if $took <= 10 else 1)" || bad "the other ranks took $took s to stop (more than 10 s)"
  grep -qi 'rank 1' dies.txt || bad "the message does not name rank 1: $(head -5 dies.txt)"
  [ -e dies/run.json ] && bad "the killed run published its folder"
fi
exit $fail
