# Shared by the cli/*.sh tests: a scratch folder removed on exit, failure bookkeeping, and
# `expect RC FRAGMENT -- command...` (exit code RC and FRAGMENT in stderr, which is printed so the
# log shows what the user would read). Sourced after `B` (the build folder) is set.
T=$(mktemp -d)
cleanup_hooks=()
on_exit() {
  local h
  for h in "${cleanup_hooks[@]}"; do eval "$h"; done
  rm -rf "$T"
}
trap on_exit EXIT
fail=0
bad() { echo "FAIL: $*"; fail=1; }
expect() {
  local want=$1 frag=$2
  shift 3
  local err rc
  err=$("$@" 2>&1 >/dev/null)
  rc=$?
  if [ "$rc" != "$want" ] || ! grep -qF -- "$frag" <<<"$err"; then
    bad "$* -> rc $rc (want $want), stderr: $err"
  else
    echo "ok (rc $rc): $(grep -F -- "$frag" <<<"$err" | head -1)"
  fi
}
# The sha256 of every file under a folder (relative names), to show a user's files unchanged.
sums() { (cd "$1" && find . -type f ! -name '.tactus-*' -print0 | sort -z | xargs -0 -r sha256sum); }
# A 4 x 4 x 4 cell rubber cube moving at 0.1 m/s for 0.05 s: DIR/cube.msh and DIR/s.toml.
cube_case() {
  mkdir -p "$1"
  "$B/data_samples/tactus-sample-mesh" --size 0.02 0.02 0.02 --cells 4 4 4 -o "$1/cube.msh" -q
  cat > "$1/s.toml" <<'TOML'
[run]
end_time = 0.05
[[bodies]]
name = "cube"
mesh = "cube.msh"
materials = { "*" = "rubber" }
initial_velocity = [0.1, 0, 0]
[materials.rubber]
type = "neo_hookean"
mu = 3000.0
bulk = 50000.0
density = 1000.0
TOML
}
