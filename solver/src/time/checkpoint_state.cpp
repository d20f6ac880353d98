// What the integrator and the contact solver save in a restart checkpoint (explicit.hpp,
// contact.hpp): every member the next step reads, by name. Scratch that each step rebuilds before
// reading it (the per-partition force arrays, the step's contact rows, the energy chunks) is left
// out. One function per class serves saving and loading (StateArchive), and each array is checked
// against the size this model gives it, so a checkpoint of another model is refused by name.
#include <algorithm>
#include <cmath>
#include <string>

#include "../contact/detection.hpp"
#include "tactus/core/state_file.hpp"
#include "tactus/solver/contact.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/rigid.hpp"

namespace tactus::solver {

namespace {

// The search state of one contact pair.
void checkpoint_search(StateArchive& a, const std::string& p, DetectionScratch& s) {
  DetectionScratch::Grid& g = s.grid;
  std::vector<double> lo(g.lo, g.lo + 3);
  std::vector<std::int32_t> n(g.n, g.n + 3);
  a.io(p + "grid.lo", lo, 3), a.io(p + "grid.n", n, 3), a.io(p + "grid.cell", g.cell);
  std::copy(lo.begin(), lo.end(), g.lo), std::copy(n.begin(), n.end(), g.n);
  a.io(p + "grid.start", g.start), a.io(p + "grid.items", g.items), a.io(p + "grid.count", g.count);
  a.io_records(p + "grid.box", g.box), a.io(p + "grid.extent", g.extent), a.io(p + "grid.normal", g.normal);
  a.io(p + "slot_triangle", s.slot_triangle), a.io(p + "slot_data", s.slot_data);
  a.io(p + "skin", s.skin);
  for (auto [name, snapshot] : {std::pair<const char*, BuildSnapshot*>{"built.", &s.built}, {"mortar.integrated.", &s.mortar.integrated}}) {
    a.io(p + name + "band", snapshot->band), a.io(p + name + "nodes", snapshot->nodes), a.io(p + name + "x", snapshot->x);
  }
  a.io(p + "candidate_start", s.candidate_start), a.io(p + "candidates", s.candidates), a.io(p + "active_triangles", s.active_triangles);
  a.io(p + "builds", s.builds), a.io(p + "searches", s.searches);
  a.io_records(p + "mortar.rows", s.mortar.rows), a.io(p + "mortar.masters", s.mortar.masters), a.io(p + "mortar.weights", s.mortar.weights);
  a.io(p + "mortar.slave_local", s.mortar.slave_local);
}

// A restored search state, checked against the pair it belongs to: every index it holds is one a
// step dereferences (a triangle, a node, a slave, a list position), so each is bounded here.
void validate_search(const StateArchive& a, const std::string& p, const DetectionScratch& s, const ContactPair& pair, std::size_t nodes) {
  const auto nt = static_cast<long long>(pair.master->triangles().size() / 3);
  const std::size_t ns = pair.slave_nodes.size();
  const auto nn = static_cast<long long>(nodes);
  const DetectionScratch::Grid& g = s.grid;
  long long cells = 1;
  for (int c = 0; c < 3; ++c) {
    if (g.n[c] < 1 || g.n[c] > (1 << 20)) a.invalid(p + "grid.n", "1 to 2^20 cells per axis", std::to_string(g.n[c]));
    cells *= g.n[c];
  }
  if (cells > (1LL << 31)) a.invalid(p + "grid.n", "at most 2^31 cells", std::to_string(cells));
  if (!(g.cell > 0) || !std::isfinite(g.cell)) a.invalid(p + "grid.cell", "a cell size > 0", std::to_string(g.cell));
  a.require_finite(p + "grid.lo", std::vector<double>(g.lo, g.lo + 3));
  if (!g.start.empty() || !g.count.empty()) {
    a.require_starts(p + "grid.count", g.count, static_cast<std::size_t>(cells), g.items.size());
    if (g.start.size() != g.count.size()) a.invalid(p + "grid.start", std::to_string(g.count.size()) + " cell ends", std::to_string(g.start.size()));
    for (std::size_t c = 0; c < g.start.size(); ++c)  // cell c spans [count[c], start[c])
      if (g.start[c] < g.count[c] || static_cast<std::size_t>(g.start[c]) > g.items.size())
        a.invalid(p + "grid.start", "cell ends within the cell's items", std::to_string(g.start[c]) + " at cell " + std::to_string(c));
  }
  a.require_indices(p + "grid.items", g.items, 0, nt);
  for (std::size_t t = 0; t < g.box.size(); ++t)
    for (int c = 0; c < 3; ++c)
      if (g.box[t][c] < 0 || g.box[t][c] > g.box[t][3 + c] || g.box[t][3 + c] >= g.n[c])
        a.invalid(p + "grid.box", "cell ranges within the grid", "triangle " + std::to_string(t));
  a.require_finite(p + "grid.extent", g.extent), a.require_finite(p + "grid.normal", g.normal);
  if (g.extent.size() > 6 * static_cast<std::size_t>(nt) || g.normal.size() > 4 * static_cast<std::size_t>(nt) ||
      g.box.size() > static_cast<std::size_t>(nt))
    a.invalid(p + "grid.box", "at most one entry per master triangle", "more");
  a.require_indices(p + "slot_triangle", s.slot_triangle, -1, nt);
  if (s.slot_triangle.size() > 2 * ns || s.slot_data.size() != 7 * s.slot_triangle.size())
    a.invalid(p + "slot_triangle", "2 slots per slave node, 7 numbers each", std::to_string(s.slot_triangle.size()) + " slots");
  a.require_finite(p + "slot_data", s.slot_data);
  if (!(s.skin >= 0) || !std::isfinite(s.skin)) a.invalid(p + "skin", "a search skin >= 0", std::to_string(s.skin));
  for (auto [name, snapshot] : {std::pair<const char*, const BuildSnapshot*>{"built.", &s.built}, {"mortar.integrated.", &s.mortar.integrated}}) {
    a.require_indices(p + name + "nodes", snapshot->nodes, 0, nn);
    if (snapshot->x.size() != 3 * snapshot->nodes.size()) a.invalid(p + name + "x", "3 coordinates per node", std::to_string(snapshot->x.size()));
    a.require_finite(p + name + "x", snapshot->x), a.require_finite(p + name + "band", snapshot->band);
  }
  if (!s.candidate_start.empty()) a.require_starts(p + "candidate_start", s.candidate_start, ns, s.candidates.size());
  a.require_indices(p + "candidates", s.candidates, 0, nt);
  a.require_indices(p + "active_triangles", s.active_triangles, 0, nt);
  a.require_indices(p + "mortar.masters", s.mortar.masters, 0, nn);
  if (s.mortar.weights.size() != s.mortar.masters.size())
    a.invalid(p + "mortar.weights", "one weight per master", std::to_string(s.mortar.weights.size()));
  a.require_finite(p + "mortar.weights", s.mortar.weights);
  a.require_indices(p + "mortar.slave_local", s.mortar.slave_local, 0, static_cast<long long>(ns));
  for (std::size_t i = 0; i < s.mortar.rows.size(); ++i) {
    const MortarRow& r = s.mortar.rows[i];
    const bool finite = std::isfinite(r.n[0]) && std::isfinite(r.n[1]) && std::isfinite(r.n[2]) && std::isfinite(r.gap) &&
                        std::isfinite(r.along_normal) && std::isfinite(r.area);
    if (r.slave_index < 0 || static_cast<std::size_t>(r.slave_index) >= ns || r.slave_node < 0 || r.slave_node >= nn || r.begin > r.end ||
        r.end > s.mortar.masters.size() || !finite)
      a.invalid(p + "mortar.rows", "rows of this pair's slaves and masters", "row " + std::to_string(i));
  }
}

}  // namespace

void ContactSolver::validate_restored(const StateArchive& a) const {
  for (std::size_t p = 0; p < pairs_.size(); ++p) {
    const std::string prefix = "contact.pair" + std::to_string(p) + ".";
    a.require_finite(prefix + "last_reaction", last_reaction_.reaction[p]);
    validate_search(a, prefix, scratch_[p], pairs_[p], model_.num_nodes);
  }
  a.require_finite("contact.windowed_pressure", windowed_pressure_);
  const ContactRows& r = ahead_rows_;
  const std::size_t rows = r.pair.size();
  a.require_indices("contact.ahead.pair", r.pair, 0, static_cast<long long>(pairs_.size()));
  if (r.slave_index.size() != rows || r.normal.size() != 3 * rows || r.gap.size() != rows || r.area.size() != rows)
    a.invalid("contact.ahead", "one slave, normal, gap and area per row", std::to_string(rows) + " rows with other counts");
  for (std::size_t i = 0; i < rows; ++i)
    if (r.slave_index[i] < 0 || static_cast<std::size_t>(r.slave_index[i]) >= pairs_[static_cast<std::size_t>(r.pair[i])].slave_nodes.size())
      a.invalid("contact.ahead.slave_index", "a slave of the row's pair", std::to_string(r.slave_index[i]) + " at row " + std::to_string(i));
  a.require_starts("contact.ahead.start", r.start, rows, r.nodes.size());
  if (r.start.empty() && rows) a.invalid("contact.ahead.start", "row starts", "none");
  a.require_indices("contact.ahead.nodes", r.nodes, 0, static_cast<long long>(model_.num_nodes));
  if (r.weights.size() != r.nodes.size()) a.invalid("contact.ahead.weights", "one weight per node", std::to_string(r.weights.size()));
  a.require_finite("contact.ahead.weights", r.weights), a.require_finite("contact.ahead.normal", r.normal);
  a.require_finite("contact.ahead.gap", r.gap), a.require_finite("contact.ahead.area", r.area);
}

void ContactSolver::checkpoint(StateArchive& a) {
  for (std::size_t p = 0; p < pairs_.size(); ++p) {
    const std::string prefix = "contact.pair" + std::to_string(p) + ".";
    a.io(prefix + "last_reaction", last_reaction_.reaction[p], last_reaction_.reaction[p].size());
    checkpoint_search(a, prefix, scratch_[p]);
  }
  a.io("contact.windowed_pressure", windowed_pressure_, windowed_pressure_.size());
  if (a.loading()) last_reaction_.find_written(), find_pressed();
  a.io("contact.pressure_window", pressure_window_);
  a.io("contact.windowed_normal_force", windowed_normal_force_), a.io("contact.windowed_area", windowed_area_);
  a.io("contact.ahead", ahead_);
  ContactRows& r = ahead_rows_;  // its geometry (the solve fills the rest)
  a.io("contact.ahead.pair", r.pair), a.io("contact.ahead.slave_index", r.slave_index), a.io("contact.ahead.start", r.start);
  a.io("contact.ahead.nodes", r.nodes), a.io("contact.ahead.weights", r.weights), a.io("contact.ahead.normal", r.normal);
  a.io("contact.ahead.gap", r.gap), a.io("contact.ahead.area", r.area);
  if (a.loading()) validate_restored(a);
}

void ExplicitSolver::checkpoint(StateArchive& a) {
  // What the model and scenario fix (the constructor computed them): a checkpoint must agree.
  const double user_dt = user_dt_, initial_critical = initial_critical_;
  // Per dof and per node (sizes fixed by the model).
  for (auto [name, v] : {std::pair<const char*, std::vector<double>*>{"u", &u_},
                         {"v_half", &v_half_},
                         {"v_prev_half", &v_prev_half_},
                         {"force", &f_},
                         {"inverse_mass", &masses_.inverse_mass},
                         {"contact_inverse_mass", &masses_.contact_inverse_mass},
                         {"nodal_mass", &masses_.mass},
                         {"prescribed_velocity", &prescribed_v_},
                         {"pressure_force", &pressure_force_},
                         {"support_force", &support_force_},
                         {"curve_at_next", &curve_at_next_},
                         {"curve_increment", &curve_increment_},
                         {"reaction_force", &reactions_.force},
                         {"reaction_moment", &reactions_.moment},
                         {"pending_added_mass", &masses_.pending_added},
                         {"added_mass_body", &masses_.added_to_body},
                         {"body_mass", &masses_.body_mass}})
    a.io(std::string("integrator.") + name, *v, v->size());
  if (a.loading() && masses_.on()) masses_.recount_raised();
  if (mass_scaling()) {  // per tet, whole: each process holds its own tets' (on ranks gathered to rank 0, whose part holds them)
    std::vector<double> factors = a.loading() ? std::vector<double>() : passes_->mass_factors_everywhere();
    if (a.loading() || !factors.empty()) a.io("integrator.mass_factor", factors, model_.num_elements);
    if (a.loading()) passes_->set_mass_factors(factors);
  }
  a.io_record("integrator.added_momentum", masses_.added_momentum);
  a.io_record("integrator.stress_pass", pass_);
  a.io_record("integrator.energies", audit_.energy);
  a.io_record("integrator.contact_report", contact_report_);
  for (auto [name, x] : {std::pair<const char*, double*>{"gravity_factor", &gravity_factor_},
                         {"pending_contact_normal", &audit_.pending_contact_normal},
                         {"pending_contact_friction", &audit_.pending_contact_friction},
                         {"stress_seconds", &stress_seconds_},
                         {"contact_seconds", &contact_seconds_},
                         {"detection_ahead_seconds", &detection_ahead_seconds_},
                         {"time", &time_},
                         {"dt_prev", &dt_prev_},
                         {"dt_next", &dt_next_},
                         {"user_dt", &user_dt_},
                         {"nominal_next", &nominal_next_},
                         {"min_step_ratio", &min_step_ratio_},
                         {"initial_critical", &initial_critical_},
                         {"pending_external", &audit_.pending_external},
                         {"pending_damping", &audit_.pending_damping}})
    a.io(std::string("integrator.") + name, *x);
  a.io("integrator.step", step_);
  a.io("integrator.next_target", next_target_);
  a.io("integrator.next_lands", next_lands_);
  a.io("integrator.velocity_advanced", velocity_advanced_);
  checkpoint_rigid_bodies(a, rigid_.bodies_for_checkpoint());
  if (drive_) drive_->checkpoint(a);
  relaxation_.checkpoint(a);
  contact_.checkpoint(a);
  if (a.loading()) {
    if (user_dt_ != user_dt || initial_critical_ != initial_critical)
      a.invalid("integrator.user_dt",
                "the step this scenario and model give (" + std::to_string(user_dt) + ", critical " + std::to_string(initial_critical) + " s)",
                std::to_string(user_dt_) + ", critical " + std::to_string(initial_critical_) + " s");
    validate_restored(a);
  }
}

void ExplicitSolver::validate_restored(const StateArchive& a) {
  for (auto [name, v] : {std::pair<const char*, const std::vector<double>*>{"u", &u_},
                         {"v_half", &v_half_},
                         {"v_prev_half", &v_prev_half_},
                         {"force", &f_},
                         {"inverse_mass", &masses_.inverse_mass},
                         {"nodal_mass", &masses_.mass},
                         {"prescribed_velocity", &prescribed_v_},
                         {"body_mass", &masses_.body_mass}})
    a.require_finite(std::string("integrator.") + name, *v);
  for (std::size_t i = 0; i < masses_.mass.size(); ++i)
    if (!(masses_.mass[i] >= 0) || !(masses_.inverse_mass[3 * i] >= 0))
      a.invalid("integrator.nodal_mass", "masses >= 0", "node " + std::to_string(i));
  if (pass_.limiting_element >= model_.num_elements || pass_.min_jacobian_element >= model_.num_elements || pass_.limiting_node >= model_.num_nodes)
    a.invalid("integrator.stress_pass", "an element and a node of this model", "an index out of range");
  // Times against the run: a step that never reaches the end, or an end already passed, hangs or
  // skips the run.
  const double end = run_.end_time;
  if (!(time_ >= 0 && time_ <= end))
    a.invalid("integrator.time", "a time from 0 to the run's end time " + std::to_string(end) + " s", std::to_string(time_));
  if (!(dt_next_ > 0 && dt_next_ <= end) || !(dt_prev_ >= 0 && dt_prev_ <= end))
    a.invalid("integrator.dt_next", "steps > 0 and within the run's end time", std::to_string(dt_next_) + " and " + std::to_string(dt_prev_));
  // The nominal step only shrinks with the stable step; far below the initial one the run would
  // take forever (a checkpoint with a tiny step hung the run).
  const double floor = 1e-4 * (user_dt_ > 0 ? std::min(user_dt_, initial_critical_) : initial_critical_ * run_.time_step_safety);
  if (!(nominal_next_ >= floor && std::isfinite(nominal_next_)) || dt_next_ > nominal_next_ * (1 + 1e-9) ||
      !(min_step_ratio_ > 0 && min_step_ratio_ <= 1 + 1e-9))
    a.invalid("integrator.nominal_next", "a step of at least " + std::to_string(floor) + " s, the step taken no larger",
              std::to_string(nominal_next_) + " (step " + std::to_string(dt_next_) + ", ratio " + std::to_string(min_step_ratio_) + ")");
  if (next_target_ >= schedule_.size())
    a.invalid("integrator.next_target", "an output time of the run's schedule (fewer than " + std::to_string(schedule_.size()) + ")",
              std::to_string(next_target_));
  for (const RigidBody& r : rigid_.bodies()) {
    const Vec3d* vectors[] = {&r.centre, &r.momentum, &r.angular_momentum, &r.force, &r.moment};
    for (const Vec3d* v : vectors)
      if (!v->allFinite()) a.invalid("rigid." + r.name, "finite numbers", "a non-finite value");
    if (!r.rotation.allFinite() || (r.rotation.transpose() * r.rotation - Mat3::Identity()).norm() > 1e-6)
      a.invalid("rigid." + r.name + ".rotation", "a rotation matrix", "a matrix that is not one");
  }
  // The state must be the one its energies describe: the strain energy of the restored
  // displacements, computed again, against the one the checkpoint stored (edited displacements of
  // 1e300 once ran on to an 18 % energy error). The sum's order may differ with the thread count.
  std::vector<double> force(f_.size());
  const StressPassResult again = passes_->compute_alone(u_.data(), v_half_.data(), force.data());
  const double stored = pass_.strain_energy;
  const double scale = std::max({std::abs(stored), audit_.energy.scale(), 1e-300});
  if (!(again.min_jacobian > 0) || !std::isfinite(again.strain_energy) || std::abs(again.strain_energy - stored) > 1e-8 * scale)
    a.invalid("integrator.u", "displacements whose strain energy is the stored " + std::to_string(stored) + " J",
              "displacements giving " + std::to_string(again.strain_energy) + " J (min J " + std::to_string(again.min_jacobian) + ")");
  check_energy();
}

}  // namespace tactus::solver
