#pragma once
// Output times and landing on them exactly.
//
// The states a run writes are at exact times: every time of run.output_times, every k * interval
// (computed from k, never by summing), and always run.end_time. The step follows the stable limit
// (the nominal step: time_step_safety x the critical step, or the user's time_step), and near each
// of these times it is adjusted so the run lands on it exactly, with no step below half the
// nominal one: when the remainder is at most one nominal step it is taken in one step (never above
// the stable limit); when it is less than two nominal steps it is split into two equal steps.
#include <vector>

#include "tactus/solver/run_settings.hpp"

namespace tactus::solver {

// Sorted, without duplicates (closer than 1e-12 of end_time), ending with end_time.
std::vector<double> output_schedule(const RunSpec& run);

struct StepChoice {
  double dt = 0;
  bool lands = false;  // after this step the time is exactly the target
};

// The next step with `remaining` (> 0) left before the next target; `nominal` <= `stable_limit`.
StepChoice choose_landing_step(double remaining, double nominal, double stable_limit);

}  // namespace tactus::solver
