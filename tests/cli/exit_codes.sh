#!/usr/bin/env bash
# cli/exit_codes: every executable answers bad input with exit 1 and one line naming the file,
# usage errors with exit 2, --help/--version with 0, and leaves no output behind.
# Usage: exit_codes.sh BUILD_DIR
set -u
B=$1
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail=0
check() {  # check EXPECTED_RC FRAGMENT -- command...
  local want=$1 frag=$2
  shift 3
  local err rc
  err=$("$@" 2>&1 >/dev/null)
  rc=$?
  if [ "$rc" != "$want" ] || ! grep -qF -- "$frag" <<<"$err" || [ "$(printf '%s\n' "$err" | grep -c .)" -gt 2 ]; then
    echo "FAIL: $* -> rc $rc (want $want), stderr: $err"
    fail=1
  fi
}
for exe in data_samples/tactus-phantom data_samples/tactus-sample-mesh segment/tactus-segment mesher/tactus-mesh solver/tactus-solve postproc/tactus-post; do
  check 0 "" -- "$B/$exe" --version
  check 2 "" -- "$B/$exe" --no-such-option
done
check 1 "no such folder" -- "$B/segment/tactus-segment" "$T/none" -o "$T/out"
check 1 "expected an HDF5 file" -- "$B/mesher/tactus-mesh" /etc/hostname -o "$T/mesh"
check 2 "scenario" -- "$B/solver/tactus-solve"
printf '[run]\nend_time = 1e-3\n' > "$T/nobody.toml"
check 1 "one or more [[bodies]] sections" -- "$B/solver/tactus-solve" "$T/nobody.toml" -o "$T/results"
cat > "$T/bad.toml" <<'TOML'
[run]
end_time = -1
[[bodies]]
name = "b"
mesh = "b.msh"
materials = { "*" = "m" }
[materials.m]
type = "neo_hookean"
mu = 1e3
bulk = 1e4
density = 1000
TOML
check 1 "run.end_time: expected a value > 0 in s, found -1" -- "$B/solver/tactus-solve" "$T/bad.toml" -o "$T/results"
check 1 "closed 2-manifold" -- "$B/mesher/tactus-mesh" stl "$(dirname "$0")/open_triangle.stl" -o "$T/obj.msh"
check 1 "expected a results folder written by tactus-solve, found no such folder" -- "$B/postproc/tactus-post" "$T/none" -o "$T/report" --no-pictures
mkdir -p "$T/empty_results"
check 1 "results.pvd: expected the results listing results.pvd" -- "$B/postproc/tactus-post" "$T/empty_results" -o "$T/report" --no-pictures
check 1 "expected a CT input" -- /usr/bin/python3 "$(dirname "$0")/../../pipeline/tactus-pipeline" "$T/none" "$T/bad.toml" -o "$T/work"
# Nothing half-written was left.
leftovers=$(find "$T" -name '*.partial-*' -o -name 'results' -o -name 'out' -o -name 'mesh' -o -name 'obj.msh' -o -name 'report' -o -name 'work')
[ -z "$leftovers" ] || { echo "FAIL: outputs left behind: $leftovers"; fail=1; }
[ $fail = 0 ] && echo "all exit-code checks passed"
exit $fail
