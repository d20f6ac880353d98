#!/usr/bin/env bash
# The hand-block meshes pinned with the solver reference, unpacked into DIR as the scenario reads
# them (DIR/mesh/mesh.msh, DIR/mesh/fibres.vtu, DIR/object/block.msh). CGAL's refinement is
# reproducible for one binary but not across builds (a change anywhere in the mesher's translation
# unit or another CPU moves a few nodes by an ulp, and the Delaunay refinement then takes another
# path), so the references and benchmarks of the solver run on these stored meshes.
#   bench/references/hand_block_meshes.sh DIR      (TACTUS_BUILD_DIR: default build/)
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
B=${TACTUS_BUILD_DIR:-$ROOT/build}
DIR=$1
mkdir -p "$DIR/mesh" "$DIR/object"
/usr/bin/python3 - "$ROOT/bench/references" "$DIR" <<'PY'
import lzma, shutil, sys
ref, out = sys.argv[1], sys.argv[2]
for stored, path in (("hand_block_hand.msh.xz", "mesh/mesh.msh"), ("hand_block_block.msh.xz", "object/block.msh")):
    with lzma.open(f"{ref}/{stored}") as src, open(f"{out}/{path}", "wb") as dst:
        shutil.copyfileobj(src, dst)
PY
"$B/mesher/tactus-mesh" fibres "$DIR/mesh/mesh.msh" --angle 30 --axis z -o "$DIR/mesh/fibres.vtu" -q --force
