#include "tactus/solver/schedule.hpp"

#include <algorithm>
#include <cmath>

namespace tactus::solver {

std::vector<double> output_schedule(const RunSpec& run) {
  std::vector<double> times = run.output_times;
  if (run.output_interval > 0) {
    const auto count = static_cast<long long>(std::floor(run.end_time / run.output_interval * (1 + 1e-12)));
    for (long long k = 1; k <= count; ++k) times.push_back(std::min(static_cast<double>(k) * run.output_interval, run.end_time));
  }
  times.push_back(run.end_time);
  std::sort(times.begin(), times.end());
  const double tol = 1e-12 * run.end_time;
  std::vector<double> out;
  for (double t : times) {
    if (t < 0 || t > run.end_time) continue;
    if (!out.empty() && t - out.back() <= tol) {
      out.back() = std::max(out.back(), t);  // keep the later (end_time over its near-twin)
      continue;
    }
    out.push_back(t);
  }
  if (out.back() != run.end_time) out.back() = run.end_time;
  return out;
}

StepChoice choose_landing_step(double remaining, double nominal, double stable_limit) {
  // One step when the remainder is at most a nominal step (1e-6 relative slack absorbs the round-off
  // of summed steps, so a fixed user step lands in one step instead of two halves), never above the
  // stable limit.
  if (remaining <= std::min(nominal * (1 + 1e-6), stable_limit)) return {remaining, true};
  if (remaining < 2 * nominal) return {0.5 * remaining, false};  // both halves in [nominal/2, nominal)
  return {nominal, false};
}

}  // namespace tactus::solver
