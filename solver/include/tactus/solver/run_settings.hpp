#pragma once
// The explicit integrator's parameters ([run] and [damping] of scenario.toml, or set in code):
// plain structs the solver takes; the scenario reader fills them (scenario.hpp).
#include <string>
#include <vector>

#include "tactus/core/vec3.hpp"

namespace tactus::solver {

// The critical step: the larger of the element estimate and a bound from each node's whole mass
// (nodal), or the element estimate alone (element; what explicit codes call element-by-element).
// design.md "The stable step".
enum class StepEstimate { nodal, element };

struct RunSpec {
  double end_time = 0;
  double time_step_safety = 0.9;
  double time_step = 0;          // 0: automatic (safety x critical step)
  bool force_time_step = false;  // accept a user time_step above the stable limit
  StepEstimate step_estimate = StepEstimate::nodal;
  std::vector<double> output_times;
  double output_interval = 0;
  double energy_tolerance = 0.25;  // relative energy-balance error that stops a run as unstable
  Vec3 gravity{0, 0, 0};
  double gravity_ramp_time = 0;
  std::string gravity_curve;   // [curves] name scaling gravity (empty: the linear ramp above, or constant)
  int threads = 0;             // 0: all cores
  int history_every = 0;       // 0: automatic (about 2000 rows)
  double max_outputs = 10000;  // runaway guards: refused above these
  double max_steps = 1e7;
  // Mass scaling: tets whose stable step falls below minimum_time_step get mass until it is met
  // (0: off); the run stops when a body's added mass exceeds added_mass_limit of its mass.
  double minimum_time_step = 0;
  double added_mass_limit = 0.01;
  // Restart checkpoints (checkpoint.hpp): every checkpoint_interval of simulated time and every
  // checkpoint_wall_interval of wall-clock time (0: off), and on an interrupt when either is on.
  double checkpoint_interval = 0, checkpoint_wall_interval = 0;
  bool checkpoints() const { return checkpoint_interval > 0 || checkpoint_wall_interval > 0; }
};

struct DampingSpec {
  double alpha = 0;  // 1/s, mass-proportional
  double beta = 0;   // s, stiffness-proportional (evaluated as a viscous stress)
  // Dynamic relaxation (relaxation.hpp): alpha each step from the relaxing mode, and the run's stop
  // once the out-of-balance force is this fraction of the internal force (0: never) after residual_after.
  bool adaptive = false;
  double residual_tolerance = 0;
  double residual_after = 0;  // s
};

}  // namespace tactus::solver
