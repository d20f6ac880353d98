// Loading (loading.hpp): time curves, the prescribed motions of the supports, follower pressures
// and the reactions, as the explicit solver applies them at every step.
#include <algorithm>
#include <cmath>

#include "tactus/solver/explicit.hpp"

namespace tactus::solver {

double CurveSpec::at(double t) const {
  if (smooth_step) {
    const double s = std::clamp((t - t0) / (t1 - t0), 0.0, 1.0);
    return s * s * (3.0 - 2.0 * s);
  }
  if (t <= times.front()) return values.front();
  if (t >= times.back()) return values.back();
  const std::size_t k = static_cast<std::size_t>(std::upper_bound(times.begin(), times.end(), t) - times.begin());  // times[k-1] < t < times[k]
  const double w = (t - times[k - 1]) / (times[k] - times[k - 1]);
  return values[k - 1] + w * (values[k] - values[k - 1]);
}

double CurveSpec::integral(double t) const {
  if (t <= 0) return 0;
  if (smooth_step) {
    // The integral of 3s^2 - 2s^3 over s is s^3 - s^4/2; in time, times (t1 - t0).
    const double h = t1 - t0, s = std::clamp((t - t0) / h, 0.0, 1.0);
    return h * (s * s * s - 0.5 * s * s * s * s) + std::max(0.0, t - t1);
  }
  // Trapezoids between the table's points, the end values held beyond them.
  double sum = 0, prev_t = 0, prev_v = at(0);
  auto add_to = [&](double tk) {
    const double vk = at(tk);
    sum += 0.5 * (prev_v + vk) * (tk - prev_t);
    prev_t = tk, prev_v = vk;
  };
  for (double tk : times) {
    if (tk <= prev_t) continue;
    if (tk >= t) break;
    add_to(tk);
  }
  add_to(t);
  return sum;
}

void ExplicitSolver::init_loading() {
  const std::size_t ndof = 3 * model_.num_nodes;
  auto curve_of = [&](std::size_t i) { return model_.constraint_curve.empty() ? -1 : model_.constraint_curve[i]; };
  prescribed_v_.assign(ndof, 0.0);
  for (std::size_t i = 0; i < ndof; ++i) {
    if (!model_.constrained[i]) continue;
    constrained_dofs_.push_back(static_cast<std::int32_t>(i));
    const bool displacement = model_.constrained[i] == 2;
    if (displacement || curve_of(i) >= 0) driven_dofs_.push_back(static_cast<std::int32_t>(i));
    // v^{-1/2}: the prescribed velocity at t = 0 (a displacement starts from rest).
    if (!displacement) prescribed_v_[i] = model_.constraint_velocity[i] * model_.curve_at(curve_of(i), 0.0);
  }
  support_force_.assign(constrained_dofs_.size(), 0.0);
  curve_at_next_.assign(model_.curves.size(), 0.0);
  curve_increment_.assign(model_.curves.size(), 0.0);
  reactions_.force.assign(3 * model_.boundaries.size(), 0.0);
  reactions_.moment.assign(3 * model_.boundaries.size(), 0.0);
  if (!model_.pressure_loads.empty()) pressure_force_.assign(ndof, 0.0);
}

void ExplicitSolver::apply_loading(double t_next, double dt) {
  // Prescribed motions, exact at t_next: a displacement value x C(t), or a velocity whose
  // integral value x I(t) is the displacement. Each curve is evaluated once per step, not per dof.
  if (!driven_dofs_.empty())
    for (std::size_t c = 0; c < model_.curves.size(); ++c) {
      curve_at_next_[c] = model_.curves[c].at(t_next);
      curve_increment_[c] = model_.curves[c].integral(t_next) - model_.curves[c].integral(time_);
    }
  for (const std::int32_t d : driven_dofs_) {
    const auto i = static_cast<std::size_t>(d);
    const std::int32_t c = model_.constraint_curve.empty() ? -1 : model_.constraint_curve[i];
    const double value = model_.constraint_velocity[i];
    if (model_.constrained[i] == 2)
      prescribed_v_[i] = (value * (c < 0 ? 1.0 : curve_at_next_[static_cast<std::size_t>(c)]) - u_[i]) / dt;
    else
      prescribed_v_[i] = value * curve_increment_[static_cast<std::size_t>(c)] / dt;
  }
  if (model_.gravity_curve >= 0)
    gravity_factor_ = model_.curve_at(model_.gravity_curve, time_);
  else if (run_.gravity_ramp_time > 0)
    gravity_factor_ = std::min(1.0, time_ / run_.gravity_ramp_time);
  else
    gravity_factor_ = 1.0;
  if (pressure_force_.empty()) return;
  // Follower pressure: -p (n A) / 3 on each node of a triangle, n A its current area normal
  // (outward of the body), so the load turns and stretches with the surface.
  std::fill(pressure_force_.begin(), pressure_force_.end(), 0.0);
  for (const PressureLoad& load : model_.pressure_loads) {
    const double p = load.pressure * model_.curve_at(load.curve, time_);
    if (p == 0) continue;
    for (std::size_t t = 0; t + 2 < load.triangles.size(); t += 3) {
      double x[3][3];
      for (int a = 0; a < 3; ++a)
        for (int c = 0; c < 3; ++c) {
          const std::size_t dof = 3 * static_cast<std::size_t>(load.triangles[t + static_cast<std::size_t>(a)]) + static_cast<std::size_t>(c);
          x[a][c] = model_.X[dof] + u_[dof];
        }
      const double e1[3] = {x[1][0] - x[0][0], x[1][1] - x[0][1], x[1][2] - x[0][2]};
      const double e2[3] = {x[2][0] - x[0][0], x[2][1] - x[0][1], x[2][2] - x[0][2]};
      const double nA[3] = {0.5 * (e1[1] * e2[2] - e1[2] * e2[1]), 0.5 * (e1[2] * e2[0] - e1[0] * e2[2]), 0.5 * (e1[0] * e2[1] - e1[1] * e2[0])};
      for (int a = 0; a < 3; ++a)
        for (int c = 0; c < 3; ++c)
          pressure_force_[3 * static_cast<std::size_t>(load.triangles[t + static_cast<std::size_t>(a)]) + static_cast<std::size_t>(c)] -=
              p * nA[c] / 3.0;
    }
  }
}

void ExplicitSolver::accumulate_reactions() {
  std::fill(reactions_.force.begin(), reactions_.force.end(), 0.0);
  std::fill(reactions_.moment.begin(), reactions_.moment.end(), 0.0);
  if (model_.constraint_boundary.empty()) return;
  for (std::size_t k = 0; k < constrained_dofs_.size(); ++k) {
    const auto i = static_cast<std::size_t>(constrained_dofs_[k]);
    const std::int32_t b = model_.constraint_boundary[i];
    if (b < 0) continue;
    const auto bb = static_cast<std::size_t>(b);
    const std::size_t node = i / 3, c = i % 3;
    const double R = support_force_[k];
    reactions_.force[3 * bb + c] += R;
    // M += r x (R e_c), r = x - moment_about at t^n.
    double r[3];
    for (std::size_t d = 0; d < 3; ++d) r[d] = model_.X[3 * node + d] + u_[3 * node + d] - model_.boundaries[bb].moment_about[d];
    double* M = &reactions_.moment[3 * bb];
    if (c == 0) M[1] += r[2] * R, M[2] -= r[1] * R;
    if (c == 1) M[2] += r[0] * R, M[0] -= r[2] * R;
    if (c == 2) M[0] += r[1] * R, M[1] -= r[0] * R;
  }
}

}  // namespace tactus::solver
