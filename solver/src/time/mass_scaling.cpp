#include "tactus/solver/mass_scaling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "tactus/solver/internal_force.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/rigid.hpp"

namespace tactus::solver {

MassScaling::MassScaling(const Model& model, double floor) : model_(model), floor_(floor) {
  const std::size_t ndof = 3 * model.num_nodes;
  mass = model.mass;
  inverse_mass.resize(ndof);
  contact_inverse_mass.resize(ndof);
  for (std::size_t i = 0; i < ndof; ++i) {
    inverse_mass[i] = 1.0 / model.mass[i / 3];
    contact_inverse_mass[i] = model.constrained[i] ? 0.0 : inverse_mass[i];
  }
  if (!on()) return;
  pending_added.assign(model.num_nodes, 0.0);
  added_to_body.assign(model.bodies.size(), 0.0);
  body_mass.assign(model.bodies.size(), 0.0);
  // Each body's mass in tet order (before the model releases its volumes on ranks: the tets below
  // the floor then bring their own rho V, FloorTet).
  for (const MaterialBlock& b : model.blocks)
    for (std::size_t e = b.begin; e < b.end; ++e)
      body_mass[model.body_of_tet(static_cast<std::size_t>(model.input_element[e]))] += b.material.density() * model.volume[e];
}

void MassScaling::scale(const std::vector<FloorTet>& below, const RigidBodies& rigid) {
  for (const FloorTet& t : below) {
    const std::size_t body = model_.body_of_tet(static_cast<std::size_t>(model_.input_element[t.tet]));
    const double added = t.rho_v * (t.factor_after - t.factor_before);  // as rho V is one product
    for (const std::int32_t node : t.nodes) {
      const auto n = static_cast<std::size_t>(node);
      if (rigid.holds(n)) {
        added_to_body[body] -= 0.25 * added;
        continue;
      }
      mass[n] += 0.25 * added;
      if (pending_added[n] == 0) raised_.push_back(static_cast<std::uint32_t>(n));
      pending_added[n] += 0.25 * added;
      for (std::size_t d = 3 * n; d < 3 * n + 3; ++d) {
        inverse_mass[d] = 1.0 / mass[n];
        contact_inverse_mass[d] = model_.constrained[d] ? 0.0 : inverse_mass[d];
      }
    }
    added_to_body[body] += added;
  }
  std::sort(raised_.begin(), raised_.end());
}

void MassScaling::take_scaled_step(StressPassResult& pass, const std::pair<double, std::size_t>& smallest) {
  // Every scaled tet now sits at the floor; the nodal bound of the pass holds a fortiori with the
  // added mass.
  pass.element_critical_step = smallest.first;
  pass.limiting_element = smallest.second;
  pass.limited_by_node = pass.nodal_critical_step > smallest.first;
  pass.critical_step = std::max(smallest.first, pass.nodal_critical_step);
}

std::ptrdiff_t MassScaling::body_over(double limit) const {
  for (std::size_t b = 0; b < body_mass.size(); ++b)
    if (added_to_body[b] > limit * body_mass[b]) return static_cast<std::ptrdiff_t>(b);
  return -1;
}

void MassScaling::book_added(const double* v_old, const double* v_new, bool first, double& kinetic) {
  for (const std::uint32_t n : raised_) {
    for (std::size_t d = 3 * n; d < 3 * n + 3; ++d) {
      const double v_n = first ? v_old[d] : 0.5 * (v_old[d] + v_new[d]);
      kinetic += 0.5 * pending_added[n] * v_n * v_n;
      added_momentum[d % 3] += pending_added[n] * v_old[d];
    }
    pending_added[n] = 0;
  }
  raised_.clear();
}

void MassScaling::forget_added() {
  for (const std::uint32_t n : raised_) pending_added[n] = 0;
  raised_.clear();
}

void MassScaling::recount_raised() {
  raised_.clear();
  for (std::size_t n = 0; n < pending_added.size(); ++n)
    if (pending_added[n] != 0) raised_.push_back(static_cast<std::uint32_t>(n));
}

}  // namespace tactus::solver
