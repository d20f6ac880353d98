#!/usr/bin/env bash
# The restart test's pad (cli/restart.sh), also run on MPI ranks (ranks/solve.sh): a pad with a
# bone inclusion (ANP hgo + linear elastic) hits a block (neo-Hookean) through mortar contact with
# friction and slides onto a rigid wall (node to surface, Verlet lists), with mass scaling and mass
# damping on. Writes pad.msh, block.msh and s.toml into the current folder.
# Usage: source pad_case.sh (with B set to the build folder)
"$B/data_samples/tactus-sample-mesh" --size 0.02 0.02 0.008 --cells 8 8 4 --inclusion -1 -1 -1 1 1 0.003 -o pad.msh -q
"$B/data_samples/tactus-sample-mesh" --size 0.03 0.03 0.01 --origin -0.005 -0.005 -0.0102 --cells 7 7 3 -o block.msh -q
cat > s.toml <<'TOML'
[run]
end_time = 1.0e-3
output_times = [0.25e-3, 0.5e-3, 0.75e-3]
checkpoint_interval = 0.2e-3
history_every = 7
minimum_time_step = 1.3e-6
added_mass_limit = 0.5
[damping]
alpha = 50.0
[[bodies]]
name = "pad"
mesh = "pad.msh"
materials = { soft_tissue = "skin", bone = "bone" }
initial_velocity = [0.6, 0.2, -2.0]
[[bodies]]
name = "block"
mesh = "block.msh"
materials = { "*" = "block" }
[materials.skin]
type = "hgo"
c1 = 10206.9
k1 = 1.7
k2 = 882.847
k = 1.0e7
formulation = "anp"
density = 1050.0
fibres = [[0.8660254, 0.5, 0.0], [0.8660254, -0.5, 0.0]]
[materials.bone]
type = "linear_elastic"
E = 1.0e9
nu = 0.22
density = 2150.0
[materials.block]
type = "neo_hookean"
mu = 3.0e5
bulk = 3.0e6
density = 1200.0
[[boundary]]
body = "block"
group = "zmin"
type = "fixed"
[[contact]]
slave_body = "pad"
slave_surface = "zmin"
master_body = "block"
master_surface = "zmax"
friction = 0.3
[[contact]]
slave_body = "pad"
slave_surface = "xmax"
plane = [[0.0203, 0.0, 0.0], [-1.0, 0.0, 0.0]]
friction = 0.2
TOML
