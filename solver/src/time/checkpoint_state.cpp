// What the integrator and the contact solver save in a restart checkpoint (explicit.hpp,
// contact.hpp): every member the next step reads, by name. Scratch that each step rebuilds before
// reading it (the per-partition force arrays, the step's contact rows, the energy chunks) is left
// out. One function per class serves saving and loading (StateArchive), and each array is checked
// against the size this model gives it, so a checkpoint of another model is refused by name.
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

}  // namespace

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
}

void ExplicitSolver::checkpoint(StateArchive& a) {
  // Per dof and per node (sizes fixed by the model).
  for (auto [name, v] : {std::pair<const char*, std::vector<double>*>{"u", &u_},
                         {"v_half", &v_half_},
                         {"v_prev_half", &v_prev_half_},
                         {"force", &f_},
                         {"inverse_mass", &inv_mass_},
                         {"contact_inverse_mass", &contact_inv_mass_},
                         {"nodal_mass", &mass_},
                         {"prescribed_velocity", &prescribed_v_},
                         {"pressure_force", &pressure_force_},
                         {"support_force", &support_force_},
                         {"curve_at_next", &curve_at_next_},
                         {"curve_increment", &curve_increment_},
                         {"reaction_force", &reactions_.force},
                         {"reaction_moment", &reactions_.moment},
                         {"pending_added_mass", &pending_added_mass_},
                         {"added_mass_body", &added_mass_body_},
                         {"body_mass", &body_mass_}})
    a.io(std::string("integrator.") + name, *v, v->size());
  if (mass_scaling()) a.io("integrator.mass_factor", forces_.mass_factor(), model_.num_elements);
  a.io_record("integrator.added_momentum", added_momentum_);
  a.io_record("integrator.stress_pass", pass_);
  a.io_record("integrator.energies", energy_);
  a.io_record("integrator.contact_report", contact_report_);
  for (auto [name, x] : {std::pair<const char*, double*>{"gravity_factor", &gravity_factor_},
                         {"pending_contact_normal", &pending_contact_normal_},
                         {"pending_contact_friction", &pending_contact_friction_},
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
                         {"pending_external", &pending_external_},
                         {"pending_damping", &pending_damping_}})
    a.io(std::string("integrator.") + name, *x);
  a.io("integrator.step", step_);
  a.io("integrator.next_target", next_target_);
  a.io("integrator.next_lands", next_lands_);
  a.io("integrator.velocity_advanced", velocity_advanced_);
  checkpoint_rigid_bodies(a, rigid_);
  contact_.checkpoint(a);
}

}  // namespace tactus::solver
