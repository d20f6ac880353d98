#pragma once
// From a scenario to the solver's model: the bridge between the input layer (scenario.hpp) and the
// physics (model.hpp), which knows nothing of the scenario file.
#include "tactus/solver/model.hpp"
#include "tactus/solver/scenario.hpp"

namespace tactus::solver {

// Reads every body's mesh, places it, assigns materials and constraints, lumps mass and
// reorders for locality. Throws InputError on anything inconsistent, naming scenario keys.
Model build_model(const Scenario& scenario);

}  // namespace tactus::solver
