# Shared steps of the mesh studies (bench/hand_block_mesh_study.sh, bench/ball_block_study.sh);
# sourced, with ROOT, B (the build folder) and W (the work folder) set by the study.

# A size of the level: $1 (a number or a product, e.g. "7 * 0.7") times the level's factor $2,
# printed with 6 significant digits (the mesher's options).
study_scaled() {
  /usr/bin/python3 -c "print(f'{($1) * $2:.6g}')"
}

# The scenario with its contact_solver.pressure_window set to $2 seconds, written into the work
# folder (mesh paths resolve from --meshes, so the copy may live there); prints its path, or the
# scenario itself when $2 is empty.
study_scenario_with_window() {
  local scenario=$1 window=$2
  if [ -z "$window" ]; then
    echo "$scenario"
    return
  fi
  /usr/bin/python3 "$ROOT/bench/set_pressure_window.py" "$scenario" "$W/scenario_window.toml" "$window" || return 1
  echo "$W/scenario_window.toml"
}

# A level's folder $W/$1 with mesh/ and object/, emptied first; only a folder a study made (its
# .tactus_mesh_study marker) is ever replaced.
study_level_folder() {
  local name=$1
  if [ -e "$W/$name" ]; then
    [ -f "$W/$name/.tactus_mesh_study" ] || { echo "$W/$name exists and was not made by this study; not replaced" >&2; exit 2; }
    rm -rf "${W:?}/$name"
  fi
  mkdir -p "$W/$name/mesh" "$W/$name/object" && touch "$W/$name/.tactus_mesh_study"
}

# After the level's hand (or ball) mesh $W/$1/mesh/mesh.msh: its fibres, the block at element size
# $2 m, and the scenario $3 solved into $W/$1/out.
study_fibres_block_solve() {
  local name=$1 block=$2 scenario=$3
  "$B/mesher/tactus-mesh" fibres "$W/$name/mesh/mesh.msh" --angle 30 --axis z -o "$W/$name/mesh/fibres.vtu" -q
  "$B/mesher/tactus-mesh" box --size 0.04 0.08 0.16 --origin 0 -0.06 0.04 --element-size "$block" -o "$W/$name/object/block.msh" -q
  echo "== $name mesh: solving $(basename "$scenario")"
  "$B/solver/tactus-solve" "$scenario" --meshes "$W/$name" -o "$W/$name/out" -q
}
