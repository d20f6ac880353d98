#!/usr/bin/env bash
# cli/restart: checkpoints and restart (issue "runs that survive interruption"). A pad (pad_case.sh) with a bone
# inclusion (ANP hgo + linear elastic) hits a block (neo-Hookean) through mortar contact with
# friction and slides onto a rigid wall (node to surface, Verlet lists), with mass scaling and
# mass damping on: every kind of state the integrator and contact carry between steps. The run is
# killed (SIGKILL, TACTUS_KILL_AT) at seeded steps and in every phase of a checkpoint write, then
# continued with --restart; oracle: the uninterrupted run of the same binary, byte for byte
# (results/*.vtu, results.pvd, history.csv). Also: a corrupt newest checkpoint is named and the one
# before it used; nothing to continue is one clear error; --resume continues or starts afresh.
# Usage: restart.sh BUILD_DIR
set -u
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
B=$(cd "$1" && pwd)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail=0
bad() { echo "FAIL: $*"; fail=1; }
cd "$T" || exit 1
source "$HERE/pad_case.sh"
S="$B/solver/tactus-solve"
"$S" s.toml -o full -q || { echo "FAIL: the uninterrupted run failed"; exit 1; }
steps=$(python3 -c "import json; print(json.load(open('full/run.json'))['steps'])")
contact=$(python3 -c "import json; print(json.load(open('full/run.json'))['contact']['steps_in_contact'])")
echo "uninterrupted: $steps steps, $contact in contact, checkpoints every 0.2 ms (about every $((steps / 5)) steps)"
[ "$contact" -gt 100 ] || bad "the case should be in contact for a good part of the run ($contact steps)"

same_as_full() {  # same_as_full DIR WHAT
  local f n=0
  for f in history.csv results.pvd $(cd full && ls results/*.vtu); do
    cmp -s "full/$f" "$1/$f" || { bad "$2: $f differs from the uninterrupted run"; return; }
    n=$((n + 1))
  done
  [ -e "$1/checkpoints" ] && bad "$2: the finished folder still holds its checkpoints"
  ls "$T" | grep -q "^$(basename "$1")\.partial-" && bad "$2: a staging folder is left"
  echo "  $2: $n files identical to the uninterrupted run"
}
killed_then_restarted() {  # killed_then_restarted DIR KILL_AT [more tactus-solve options]
  rm -rf "$1"
  local rc
  rc=$( (TACTUS_KILL_AT=$2 "$S" s.toml -o "$1" -q "${@:3}" >/dev/null 2>&1); echo $?) 2>/dev/null
  [ "$rc" = 137 ] || { bad "$2: expected the process killed (137), rc $rc"; return 1; }
  [ -e "$1" ] && bad "$2: a killed run left a folder that looks finished"
  return 0
}

# 1. Killed at seeded steps (and before the first checkpoint: nothing to continue).
RANDOM=2026
for k in 1 2 3; do
  step=$((200 + RANDOM % (steps - 250)))
  more=()
  [ $k = 1 ] && more=(--meshes .)  # the mesh folder given as a relative path: the restart finds the same files
  killed_then_restarted "k$k" "step:$step" "${more[@]}" || continue
  "$S" --restart "k$k" -q || { bad "restart after a kill at step $step failed"; continue; }
  same_as_full "k$k" "killed at step $step, restarted"
  grep -q '"restarted_from"' "k$k/run.json" || bad "run.json does not say the run was restarted"
done
killed_then_restarted early step:20
err=$("$S" --restart early 2>&1 >/dev/null)
rc=$?
{ [ "$rc" = 1 ] && grep -q "none: nothing to continue" <<<"$err"; } || bad "restart without a checkpoint: rc $rc, $err"
echo "  killed at step 20 (before the first checkpoint): restart refused: $(tail -1 <<<"$err")"

# 2. Killed in each phase of a checkpoint write (the second one, so a complete one exists): before
#    it, arrays written, closed, renamed, and with the part down but no manifest yet.
for phase in begin data written renamed manifest; do
  killed_then_restarted "p_$phase" "checkpoint:1:$phase" || continue
  "$S" --restart "p_$phase" -q || { bad "restart after a kill in checkpoint phase '$phase' failed"; continue; }
  same_as_full "p_$phase" "killed while writing a checkpoint ($phase)"
done

# 3. Interrupted (SIGTERM, as tactus-pipeline stops a stage): a checkpoint at that step, the
#    staging folder kept, and the restart continues from exactly there.
rm -rf stopped
err=$(TACTUS_KILL_AT=interrupt:$((steps / 2 + 7)) "$S" s.toml -o stopped -q 2>&1 >/dev/null)
rc=$?
{ [ "$rc" = 143 ] && grep -q "checkpoint written at step $((steps / 2 + 7))" <<<"$err"; } || bad "interrupt with checkpoints on: rc $rc, $err"
"$S" --restart stopped -q || bad "restart after an interrupt failed"
same_as_full stopped "interrupted (SIGTERM) at step $((steps / 2 + 7)), restarted"

# 4. A corrupt newest checkpoint: named, and the one before it used.
killed_then_restarted corrupt "step:$((steps - 60))"
newest=$(ls corrupt.partial-*/checkpoints/*.h5 | tail -1)
python3 - "$newest" <<'PY'
import sys
p = sys.argv[1]
b = bytearray(open(p, "rb").read())
b[len(b) // 2] ^= 0xFF  # one flipped byte in the middle of the arrays
open(p, "wb").write(bytes(b))
PY
err=$("$S" --restart corrupt 2>&1 >/dev/null) || bad "restart with a corrupt newest checkpoint failed: $err"
grep -qF "$(basename "$newest")" <<<"$err" || bad "the corrupt checkpoint is not named: $err"
same_as_full corrupt "newest checkpoint corrupt, previous used"
echo "    warning: $(grep -i checkpoint <<<"$err" | head -1)"

# 5. --resume (what tactus-pipeline runs): continues a killed run, else starts from t = 0.
killed_then_restarted resumed "step:$((steps / 2))"
"$S" s.toml -o resumed --resume 2>&1 | grep -q "continuing from" || bad "--resume after a kill did not continue the run"
same_as_full resumed "--resume after a kill"
rm -rf fresh
"$S" s.toml -o fresh --resume -q || bad "--resume with nothing to continue failed"
same_as_full fresh "--resume with nothing to continue (a fresh run)"

# 6. A changed input refuses the restart, naming it.
killed_then_restarted changed "step:$((steps / 2))"
sed -i 's/friction = 0.3/friction = 0.31/' s.toml
err=$("$S" --restart changed 2>&1 >/dev/null)
rc=$?
{ [ "$rc" = 1 ] && grep -q "has changed" <<<"$err"; } || bad "restart after the scenario changed: rc $rc, $err"
echo "  scenario changed after the kill: restart refused: $(tail -1 <<<"$err")"

[ $fail = 0 ] && echo "restart: all cases pass"
exit $fail
