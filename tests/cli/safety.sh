#!/usr/bin/env bash
# cli/safety: what a new user did that lost data or crashed (the bad-input probe), now refused with
# one clear message and the user's files untouched; interrupts leave nothing half-written.
# Usage: safety.sh BUILD_DIR
set -u
B=$(cd "$1" && pwd)
. "$(dirname "$0")/lib.sh"

cube_case "$T/case"

# 1. Data loss: a folder with a user's thesis, the current folder, the results being read.
mkdir -p "$T/mydata" && echo "my thesis" > "$T/mydata/thesis.tex"
expect 1 "did not write" -- "$B/solver/tactus-solve" "$T/case/s.toml" -o "$T/mydata"
[ "$(cat "$T/mydata/thesis.tex")" = "my thesis" ] || bad "thesis.tex changed"
(cd "$T/case" && expect 1 "current folder" -- "$B/solver/tactus-solve" "$T/case/s.toml" -o .)
[ -f "$T/case/s.toml" ] && [ -f "$T/case/cube.msh" ] || bad "the case folder lost files"
"$B/solver/tactus-solve" "$T/case/s.toml" -o "$T/res" -q || bad "a valid run failed"
expect 1 "is an input" -- "$B/postproc/tactus-post" "$T/res" -o "$T/res" --no-pictures
[ -f "$T/res/run.json" ] || bad "tactus-post deleted the results it read"
"$B/solver/tactus-solve" "$T/case/s.toml" -o "$T/res" -q || bad "replacing its own previous output failed"
cp -a "$T/res" "$T/other"   # another tool's output: replaced only with --force
expect 1 "holds the output of tactus-solve" -- "$B/postproc/tactus-post" "$T/res" -o "$T/other" --no-pictures
"$B/postproc/tactus-post" "$T/res" -o "$T/other" --no-pictures --force -q && [ -f "$T/other/summary.md" ] || bad "--force did not replace"
expect 1 "cannot" -- "$B/solver/tactus-solve" "$T/case/s.toml" -o "$T/case/cube.msh/out"
expect 1 "cannot" -- "$B/solver/tactus-solve" "$T/case/s.toml" -o /proc/tactus-out

# 2. Values that were ignored or crashed.
for v in 0 -1 nan; do expect 1 "--end-time" -- "$B/solver/tactus-solve" "$T/case/s.toml" -o "$T/e" --end-time "$v"; done
sed 's/end_time = 0.05/end_time = 1e11/' "$T/case/s.toml" > "$T/case/long.toml"
expect 1 "run.max_steps" -- "$B/solver/tactus-solve" "$T/case/long.toml" -o "$T/e"
cp -r "$T/res" "$T/res_bad" && sed -i 's/"steps": [0-9]*/"steps": "many"/' "$T/res_bad/run.json" && rm -f "$T/res_bad/.tactus-output.json"
expect 1 "run.json: steps" -- "$B/postproc/tactus-post" "$T/res_bad" -o "$T/rep" --no-pictures
mkdir -p "$T/nostates" && cp "$T/res/run.json" "$T/res/history.csv" "$T/nostates/" \
  && printf '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n  </Collection>\n</VTKFile>\n' > "$T/nostates/results.pvd"
expect 1 "at least one output state" -- "$B/postproc/tactus-post" "$T/nostates" -o "$T/rep" --no-pictures
expect 1 "cannot" -- "$B/mesher/tactus-mesh" box --size 1 1 1 --element-size 0.01 -o "$T/case/cube.msh/x.msh"
expect 1 "--max-elements" -- "$B/mesher/tactus-mesh" box --size 1 1 1 --element-size 0.0001 -o "$T/huge.msh"
expect 1 "edge radius" -- "$B/mesher/tactus-mesh" box --size 0.1 0.1 0.02 --edge-radius 0.01 -o "$T/round.msh"
# An unmet mesh guarantee of a gmsh object is explained in its own options (exit 0: a warning).
expect 0 "a smaller --element-size" -- "$B/mesher/tactus-mesh" box --size 0.05 0.05 0.05 --element-size 0.01 --edge-radius 0.004 -o "$T/sliver.msh"
sliver_err=$("$B/mesher/tactus-mesh" box --size 0.05 0.05 0.05 --element-size 0.01 --edge-radius 0.004 -o "$T/sliver2.msh" 2>&1 >/dev/null)
if grep -qF -- "--facet-size" <<<"$sliver_err"; then bad "tactus-mesh box: the guarantee warning names the image mesher's --facet-size: $sliver_err"; fi
expect 1 "did not write" -- "$B/data_samples/tactus-sample-mesh" -o "$T/mydata/thesis.tex"

# 3. Interrupts: SIGINT and SIGTERM stop a run cleanly; a killed run's staging is removed next time.
sed 's/end_time = 0.05/end_time = 500/; s/\[run\]/[run]\ntime_step = 1e-6\nmax_steps = 1e12/' "$T/case/s.toml" > "$T/case/slow.toml"
for sig in INT TERM; do
  "$B/solver/tactus-solve" "$T/case/slow.toml" -o "$T/slow" -q 2> "$T/sig.err" &
  pid=$!
  sleep 1.5
  kill -$sig $pid
  wait $pid
  rc=$?
  want=$([ $sig = INT ] && echo 130 || echo 143)
  [ "$rc" = "$want" ] || bad "SIG$sig: exit $rc (want $want): $(cat "$T/sig.err")"
  grep -q "interrupted (SIG$sig); partial output removed" "$T/sig.err" || bad "SIG$sig message: $(cat "$T/sig.err")"
  [ ! -e "$T/slow" ] && [ -z "$(ls -d "$T"/slow.partial-* 2>/dev/null)" ] || bad "SIG$sig left output behind"
done
"$B/solver/tactus-solve" "$T/case/slow.toml" -o "$T/slow" -q 2>/dev/null &
pid=$!
sleep 1.5
kill -9 $pid
wait $pid 2>/dev/null
[ -n "$(ls -d "$T"/slow.partial-$pid-* 2>/dev/null)" ] || bad "kill -9 left no staging folder (test premise)"
"$B/solver/tactus-solve" "$T/case/s.toml" -o "$T/slow" -q || bad "the run after the killed one failed"
[ -z "$(ls -d "$T"/slow.partial-* 2>/dev/null)" ] || bad "the stale staging of the killed run is still there"

[ $fail = 0 ] && echo "all safety checks passed"
exit $fail
