#!/usr/bin/env bash
# The main job: sets tactus up (setup.sh: Debian packages + build), makes the bundled sample and
# runs the whole chain on it with tactus-pipeline:
#   tactus-phantom   synthetic hand CT at the paper's resolution (0.7 mm)      -> out/phantom/
#   tactus-pipeline  segment -> mesh hand (CGAL) + block (gmsh) -> solve the paper's hand-block
#                    impact (pipeline/scenarios/hand_block.toml, 5 ms) -> report
#                    -> out/pipeline/{segment,mesh,object,solve,report}/
# Re-running skips the stages whose inputs did not change. Extra arguments go to tactus-pipeline
# (e.g. --end-time 0.002, --force).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
export TACTUS_BUILD_DIR=${TACTUS_BUILD_DIR:-$ROOT/build}
bash "$ROOT/scripts/setup.sh"
cd "$ROOT"
if [ ! -f out/phantom/stack.json ]; then
  echo "== phantom: synthetic hand CT (0.7 mm slices, noise 25 HU) -> out/phantom"
  "$TACTUS_BUILD_DIR/data_samples/tactus-phantom" -o out/phantom
fi
/usr/bin/python3 pipeline/tactus-pipeline out/phantom pipeline/scenarios/hand_block.toml -o out/pipeline "$@"
