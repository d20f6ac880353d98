#include "tactus/solver/explicit.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <sstream>

#include "../contact/bipotential.hpp"
#include "tactus/core/error.hpp"
#include "tactus/solver/schedule.hpp"

namespace tactus::solver {

double Energies::scale() const { return std::max({std::abs(initial), peak, std::abs(external_work), std::abs(damping_work), 1e-300}); }

ExplicitSolver::ExplicitSolver(const Model& model, const RunSpec& run, const DampingSpec& damping)
    : model_(model), run_(run), damping_(damping), forces_(model, damping.beta, run.threads), contact_(model) {
  const std::size_t ndof = 3 * model.num_nodes;
  u_.assign(ndof, 0.0);
  f_.assign(ndof, 0.0);
  v_half_ = model.initial_velocity;
  init_loading();
  for (std::size_t i = 0; i < ndof; ++i)
    if (model.constrained[i]) v_half_[i] = prescribed_v_[i];
  v_prev_half_ = v_half_;
  mass_ = model.mass;
  inv_mass_.resize(ndof);
  gravity_force_.resize(ndof);
  for (std::size_t i = 0; i < ndof; ++i) {
    inv_mass_[i] = 1.0 / model.mass[i / 3];
    gravity_force_[i] = model.mass[i / 3] * run.gravity[i % 3];  // on the physical mass, also under mass scaling
  }
  contact_inv_mass_.resize(ndof);
  for (std::size_t i = 0; i < ndof; ++i) contact_inv_mass_[i] = model.constrained[i] ? 0.0 : inv_mass_[i];
  if (mass_scaling()) {
    forces_.enable_mass_scaling();
    pending_added_mass_.assign(model.num_nodes, 0.0);
    added_mass_body_.assign(model.bodies.size(), 0.0);
    body_mass_.assign(model.bodies.size(), 0.0);
    element_body_.resize(model.num_elements);
    for (std::size_t e = 0; e < model.num_elements; ++e) {
      element_body_[e] = model.tet_body[static_cast<std::size_t>(model.input_element[e])];
      body_mass_[static_cast<std::size_t>(element_body_[e])] += model.block_of(e).material.density() * model.volume[e];
    }
  }
  rigid_.init(model_, v_half_.data(), v_prev_half_.data(), contact_inv_mass_.data());
  contact_.set_threads(forces_.threads());
  if (!contact_.empty()) contact_.check_initial_overlap(u_.data());
  schedule_ = output_schedule(run);
  while (next_target_ < schedule_.size() && schedule_[next_target_] <= 0) ++next_target_;
  stress_pass();
  initial_critical_ = pass_.critical_step;
  contact_.set_pressure_window(std::max(model.contact_settings.pressure_window, 10 * initial_critical_));
  double kinetic = rigid_.kinetic_energy(true), added = 0;  // the initial energy is the physical one; mass added at t = 0 is booked as added
  for (std::size_t i = 0; i < ndof; ++i) {
    if (rigid_.holds(i / 3)) continue;
    kinetic += 0.5 * mass_[i / 3] * v_half_[i] * v_half_[i];
    added += 0.5 * (mass_[i / 3] - model.mass[i / 3]) * v_half_[i] * v_half_[i];
    added_momentum_[i % 3] += (mass_[i / 3] - model.mass[i / 3]) * v_half_[i];
  }
  if (mass_scaling()) std::fill(pending_added_mass_.begin(), pending_added_mass_.end(), 0.0);
  energy_.kinetic = kinetic;
  energy_.internal = pass_.strain_energy;
  energy_.added_mass_kinetic = added;
  energy_.initial = kinetic - added + pass_.strain_energy;
  energy_.peak = energy_.initial;

  if (run.time_step > 0) {
    const double limit = pass_.critical_step;
    if (run.time_step > limit && !run.force_time_step) {
      std::ostringstream o;
      o << "a step <= the stable limit " << limit << " s (" << describe_step_limit()
        << "); lower it, remove it for the automatic step, or set run.force_time_step = true";
      std::ostringstream f;
      f << run.time_step << " s";
      throw InputError(model_.source, "run.time_step", o.str(), f.str());
    }
    user_dt_ = run.time_step;
  }
  if (!(user_dt_ > 0) && !std::isfinite(pass_.critical_step))
    throw InputError(model_.source, "run.time_step", "a time step (every tet is rigid: no stable limit to take it from)", "none");
  // Scheduled times closer than half a step apart cannot be landed on without tiny steps (each
  // state would repeat the one before): refused, naming them.
  const double nominal = user_dt_ > 0 ? user_dt_ : run.time_step_safety * pass_.critical_step;
  double before = 0;
  for (double t : schedule_) {
    if (t > 0 && t - before < 0.5 * nominal) {
      std::ostringstream o, f;
      if (before == 0 && t == schedule_.back()) {  // the run itself is shorter than half a step
        o << "an end time of at least half a time step (the step is " << nominal << " s, " << describe_step_limit() << ")";
        f << t << " s";
        throw InputError(model_.source, "run.end_time", o.str(), f.str());
      }
      o << "output times at least half a time step apart (the step is " << nominal << " s, " << describe_step_limit() << ")";
      f << before << " s and " << t << " s";
      throw InputError(model_.source, run.output_interval > 0 ? "run.output_interval" : "run.output_times", o.str(), f.str());
    }
    before = t;
  }
  choose_step();
}

ExplicitSolver::~ExplicitSolver() = default;

void ExplicitSolver::stress_pass(bool detect_ahead) {
  const auto t0 = std::chrono::steady_clock::now();
  // The side task must not throw out of the parallel region: its exception waits for the end.
  struct Ahead {
    ExplicitSolver* solver;
    std::exception_ptr error;
    double seconds = 0;
  } ahead{this, nullptr};
  StressSideTask side;
  if (detect_ahead && !contact_.empty())
    side = {[](void* context) {
              auto& a = *static_cast<Ahead*>(context);
              const auto start = std::chrono::steady_clock::now();
              try {
                a.solver->contact_.detect_ahead(a.solver->u_.data());
              } catch (...) {
                a.error = std::current_exception();
              }
              a.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            },
            &ahead};
  forces_.set_nodal_step_bound(run_.step_estimate == StepEstimate::nodal ? mass_.data() : nullptr);  // the masses the run integrates with
  pass_ = forces_.compute(u_.data(), v_half_.data(), f_.data(), side);
  stress_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  detection_ahead_seconds_ += ahead.seconds;
  if (ahead.error) std::rethrow_exception(ahead.error);
  if (!(pass_.min_jacobian > 0)) {
    std::ostringstream o;
    o << "inverted element at step " << step_ << ", t = " << time_ << " s: " << model_.describe_element(pass_.min_jacobian_element)
      << " has J = " << pass_.min_jacobian << " (the time step may be too large, or the loading too severe for this mesh)";
    throw NumericalError(o.str());
  }
  if (!std::isfinite(pass_.strain_energy)) {
    std::ostringstream o;
    o << "non-finite strain energy at step " << step_ << ", t = " << time_ << " s";
    throw NumericalError(o.str());
  }
  if (mass_scaling() && pass_.critical_step < run_.minimum_time_step) scale_mass();
}

void ExplicitSolver::scale_mass() {
  const double floor2 = run_.minimum_time_step * run_.minimum_time_step;
  std::vector<double>& factor = forces_.mass_factor();
  const std::vector<double>& dt2 = forces_.element_dt2();
  for (const MaterialBlock& b : model_.blocks) {
    if (b.material.rigid()) continue;  // no step of their own
    const double rho = b.material.density();
    for (std::size_t e = b.begin; e < b.end; ++e) {
      if (!(dt2[e] * factor[e] < floor2)) continue;
      // The tet's step grows as sqrt of its mass: (rho V + dM) / (rho V) = floor^2 / dt_e^2.
      const double target = floor2 / dt2[e];
      const double added = rho * model_.volume[e] * (target - factor[e]);
      factor[e] = target;
      for (int k = 0; k < 4; ++k) {
        const auto n = static_cast<std::size_t>(model_.conn[4 * e + static_cast<std::size_t>(k)]);
        // A node of a rigid body gets none: the body's mass is its own (and far larger).
        if (rigid_.holds(n)) {
          added_mass_body_[static_cast<std::size_t>(element_body_[e])] -= 0.25 * added;
          continue;
        }
        mass_[n] += 0.25 * added;
        pending_added_mass_[n] += 0.25 * added;
        for (std::size_t d = 3 * n; d < 3 * n + 3; ++d) {
          inv_mass_[d] = 1.0 / mass_[n];
          contact_inv_mass_[d] = model_.constrained[d] ? 0.0 : inv_mass_[d];
        }
      }
      added_mass_body_[static_cast<std::size_t>(element_body_[e])] += added;
    }
  }
  // The step with the new masses (every scaled tet now sits at the floor), as the kernel computes it.
  double best = std::numeric_limits<double>::infinity();
  for (const MaterialBlock& b : model_.blocks)
    for (std::size_t e = b.begin; e < b.end && !b.material.rigid(); ++e) {
      double dt = std::sqrt(dt2[e] * factor[e]);
      if (damping_.beta > 0) {
        const double omega = 2.0 / dt, xi = 0.5 * damping_.beta * omega;
        dt = 2.0 / omega * (std::sqrt(1.0 + xi * xi) - xi);
      }
      if (dt < best) best = dt, pass_.limiting_element = e;
    }
  // The nodal bound of the pass holds a fortiori with the added mass.
  pass_.element_critical_step = best;
  pass_.limited_by_node = pass_.nodal_critical_step > best;
  pass_.critical_step = std::max(best, pass_.nodal_critical_step);
  for (std::size_t b = 0; b < body_mass_.size(); ++b)
    if (added_mass_body_[b] > run_.added_mass_limit * body_mass_[b]) {
      std::ostringstream o;
      o << "mass scaling has added " << added_mass_body_[b] << " kg to body '" << model_.bodies[b].name << "' by step " << step_ << ", t = " << time_
        << " s: " << 100 * added_mass_body_[b] / body_mass_[b] << " % of its " << body_mass_[b]
        << " kg, above run.added_mass_limit = " << 100 * run_.added_mass_limit
        << " %, to keep the step at run.minimum_time_step = " << run_.minimum_time_step << " s (" << describe_step_limit()
        << "); lower minimum_time_step or raise added_mass_limit";
      throw NumericalError(o.str());
    }
}

void ExplicitSolver::choose_step() {
  const double nominal = user_dt_ > 0 ? user_dt_ : run_.time_step_safety * pass_.critical_step;
  // A user step may exceed the critical one only when forced; landing never adds to it.
  const double limit = user_dt_ > 0 ? std::max(user_dt_, pass_.critical_step) : pass_.critical_step;
  nominal_next_ = nominal;
  next_lands_ = false;
  if (next_target_ >= schedule_.size()) {
    dt_next_ = nominal;
    return;
  }
  const StepChoice c = choose_landing_step(schedule_[next_target_] - time_, nominal, limit);
  dt_next_ = c.dt;
  next_lands_ = c.lands;
}

std::string ExplicitSolver::describe_step_limit() const {
  std::ostringstream o;
  const std::size_t e = pass_.limiting_element;
  if (pass_.limited_by_node) {
    const std::size_t in = model_.input_node(pass_.limiting_node);  // body-local and 1-based, as the tets
    o << "limited by the nodal bound at node ";
    if (model_.bodies.empty()) {
      o << in + 1;
    } else {
      const BodyRange& body = model_.bodies[model_.body_of_node(in)];
      o << in - body.node_begin + 1 << " of body '" << body.name << "'";
    }
    o << ", critical step " << pass_.critical_step << " s (the element estimate " << pass_.element_critical_step << " s, at "
      << model_.describe_element(e) << ")";
  } else {
    o << "limited by " << model_.describe_element(e) << ", critical step " << pass_.critical_step << " s";
  }
  return o.str();
}

void ExplicitSolver::advance_velocity() {
  const std::size_t ndof = 3 * model_.num_nodes;
  const double dt = dt_next_;
  const double dtbar = 0.5 * (dt_prev_ + dt);
  const double alpha = damping_.alpha;
  const double c_minus = 1.0 - 0.5 * alpha * dtbar, c_plus = 1.0 / (1.0 + 0.5 * alpha * dtbar);
  const bool first = step_ == 0;
  apply_loading(next_lands_ ? schedule_[next_target_] : time_ + dt, dt);
  v_prev_half_.swap(v_half_);
  const double* __restrict v_old_of = v_prev_half_.data();
  double* __restrict v_new_of = v_half_.data();
  const int threads = forces_.threads();
  // Free (contact-less) prediction v^{n+1/2} of one dof, from v^{n-1/2} and the forces at t^n.
  auto free_velocity = [&](std::size_t i, double fext) { return (c_minus * v_old_of[i] + dtbar * (fext + f_[i]) * inv_mass_[i]) * c_plus; };
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::size_t i = 0; i < ndof; ++i) v_new_of[i] = model_.constrained[i] ? prescribed_v_[i] : free_velocity(i, external_force(i));
  if (!rigid_.empty())
    rigid_.kick(
        model_, f_.data(), [this](std::size_t i) { return external_force(i); }, u_.data(), time_, next_lands_ ? schedule_[next_target_] : time_ + dt,
        dt, dtbar, c_minus, c_plus);
  // Contact reactions at t^n correct it (paper eq. 35 with R): dv = dtbar c_plus M^-1 R.
  if (!contact_.empty()) {
    const auto t0 = std::chrono::steady_clock::now();
    contact_report_ =
        contact_.correct_velocities(u_.data(), v_new_of, v_old_of, contact_inv_mass_.data(), dtbar * c_plus, dt, dt_prev_, rigid_.contact_rows());
    contact_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }

  if (!rigid_.empty()) rigid_.drift(model_, u_.data(), dt, v_new_of);
  // The supports' forces: R = m (v_new - v_free) / (dtbar c_plus), exactly what the update added.
  for (std::size_t k = 0; k < constrained_dofs_.size(); ++k) {
    const auto i = static_cast<std::size_t>(constrained_dofs_[k]);
    support_force_[k] = mass_[i / 3] * (v_new_of[i] - free_velocity(i, external_force(i))) / (dtbar * c_plus);
  }
  accumulate_reactions();

  double kinetic = rigid_.kinetic_energy(first), ext_back = 0, ext_fwd = 0, damp_back = 0, damp_fwd = 0;
  const double* __restrict mass_of = mass_.data();
  const std::int32_t* rigid_of = rigid_.piece_of_node();
  if (mass_scaling()) {
    // Mass added at t^n: its kinetic energy 1/2 dm (v^n)^2, the difference it makes to the kinetic
    // energy below, and its momentum dm v^{n-1/2}: the update from v^{n-1/2} conserves the
    // momentum of the new masses, so that is what the added mass brought.
    for (std::size_t n = 0; n < model_.num_nodes; ++n) {
      if (pending_added_mass_[n] == 0) continue;
      for (std::size_t d = 3 * n; d < 3 * n + 3; ++d) {
        const double v_n = first ? v_old_of[d] : 0.5 * (v_old_of[d] + v_new_of[d]);
        energy_.added_mass_kinetic += 0.5 * pending_added_mass_[n] * v_n * v_n;
        added_momentum_[d % 3] += pending_added_mass_[n] * v_old_of[d];
      }
      pending_added_mass_[n] = 0;
    }
  }
  // The energy sums over fixed chunks of dofs, added in chunk order: the same bits for any
  // number of threads (an OpenMP reduction adds in an order that depends on it).
  const std::size_t chunks = (ndof + kEnergyChunk - 1) / kEnergyChunk;
  energy_chunks_.resize(chunks);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::size_t c = 0; c < chunks; ++c) {
    std::array<double, 5> sum{};  // kinetic, ext_back, ext_fwd, damp_back, damp_fwd
    for (std::size_t i = c * kEnergyChunk; i < std::min(ndof, (c + 1) * kEnergyChunk); ++i) {
      // A rigid body's nodes: their kinetic energy and damping are the body's (below).
      const double m = rigid_of && rigid_of[i / 3] != -1 ? 0.0 : mass_of[i / 3];
      const double fext = external_force(i);
      const double v_old = v_old_of[i], v_new = v_new_of[i];
      double reaction = 0;
      if (model_.constrained[i]) {                                           // the support force that holds the prescribed velocity
        reaction = m * (v_new - free_velocity(i, fext)) / (dtbar * c_plus);  // what the update added: dtbar c_plus R / m
      }
      const double v_n = first ? v_old : 0.5 * (v_old + v_new);
      sum[0] += 0.5 * m * v_n * v_n;
      // Work of F^n over du^{n-1/2} (closes step n-1) and du^{n+1/2} (carried to step n+1).
      const double F = fext + reaction;
      const double fdamp = alpha * m * v_n;
      sum[1] += F * dt_prev_ * v_old;
      sum[2] += F * dt * v_new;
      sum[3] += fdamp * dt_prev_ * v_old;
      sum[4] += fdamp * dt * v_new;
    }
    energy_chunks_[c] = sum;
  }
  for (const auto& sum : energy_chunks_) kinetic += sum[0], ext_back += sum[1], ext_fwd += sum[2], damp_back += sum[3], damp_fwd += sum[4];
  rigid_.add_work(alpha, dt_prev_, dt, first, damp_back, damp_fwd, ext_back, ext_fwd);
  const ContactStepReport& c = contact_report_;
  ext_back += c.support_work_back;
  ext_fwd += c.support_work_forward;
  energy_.kinetic = kinetic;
  energy_.internal = pass_.strain_energy;
  energy_.external_work += 0.5 * (pending_external_ + ext_back);
  energy_.damping_work += 0.5 * (pending_damping_ + damp_back) + pass_.viscous_power * dtbar;
  // The reactions' work on the relative motion, with the sign of energy taken out.
  energy_.contact_normal_work -= 0.5 * (pending_contact_normal_ + c.normal_work_back);
  energy_.contact_friction_work -= 0.5 * (pending_contact_friction_ + c.friction_work_back);
  pending_external_ = ext_fwd;
  pending_damping_ = damp_fwd;
  pending_contact_normal_ = c.normal_work_forward;
  pending_contact_friction_ = c.friction_work_forward;
  energy_.peak = std::max(energy_.peak, kinetic + pass_.strain_energy);
  velocity_advanced_ = true;
}

void ExplicitSolver::check_energy() const {
  const double err = energy_.balance_error();
  std::ostringstream o;
  if (!std::isfinite(err) || !std::isfinite(energy_.kinetic)) {
    o << "non-finite energy at step " << step_ << ", t = " << time_ << " s (NaN or overflow; " << describe_step_limit() << ")";
    throw NumericalError(o.str());
  }
  // Relative to the largest energy, from the tenth step on: a run starting at rest (under gravity
  // or a load ramp) has every energy O(dt^2) in its first steps, where the trapezoid rule's lag in
  // the work terms is of the same size, so their ratio says nothing (it stopped such runs at step
  // 1). An unstable step grows the energy by a factor per step and is still caught a few steps on.
  if (step_ >= 10 && std::abs(err) > run_.energy_tolerance * energy_.scale()) {
    o << "energy blow-up at step " << step_ << ", t = " << time_ << " s: energy balance error " << err << " J is " << std::abs(err) / energy_.scale()
      << " of the largest energy (tolerance run.energy_tolerance = " << run_.energy_tolerance << "); time step " << dt_next_ << " s vs "
      << describe_step_limit() << " - the step is above the stable limit or the model is unstable";
    throw NumericalError(o.str());
  }
}

void ExplicitSolver::advance_position() {
  const std::size_t ndof = 3 * model_.num_nodes;
  const double dt = dt_next_;
#pragma omp parallel for num_threads(forces_.threads()) schedule(static)
  for (std::size_t i = 0; i < ndof; ++i) u_[i] += dt * v_half_[i];
  rigid_.place(model_, u_.data());
  min_step_ratio_ = std::min(min_step_ratio_, dt / nominal_next_);
  if (next_lands_) {
    time_ = schedule_[next_target_++];  // exactly, not the sum of the steps
  } else {
    time_ += dt;
  }
  ++step_;
  dt_prev_ = dt;
  velocity_advanced_ = false;
  stress_pass(true);
  if (pass_.critical_step < 1e-3 * initial_critical_) {
    std::ostringstream o;
    o << "the stable time step collapsed to " << pass_.critical_step << " s at step " << step_ << ", t = " << time_
      << " s, below 1e-3 of the initial " << initial_critical_ << " s (" << describe_step_limit()
      << "): " << model_.describe_element(pass_.limiting_element)
      << " is being crushed or its material stiffens without bound (fibres?); the run would not finish";
    throw NumericalError(o.str());
  }
  choose_step();
}

std::size_t ExplicitSolver::memory_bytes() const {
  std::size_t doubles = u_.capacity() + v_half_.capacity() + v_prev_half_.capacity() + f_.capacity() + inv_mass_.capacity() +
                        gravity_force_.capacity() + mass_.capacity() + pending_added_mass_.capacity();
  return doubles * sizeof(double) + forces_.memory_bytes();
}

std::vector<double> ExplicitSolver::velocity_at_step() const {
  std::vector<double> v(v_half_.size());
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = step_ == 0 ? v_prev_half_[i] : 0.5 * (v_prev_half_[i] + v_half_[i]);
  return v;
}

std::vector<double> ExplicitSolver::previous_displacement() const {
  std::vector<double> u(u_.size());
  const std::vector<double>& v = velocity_advanced_ ? v_prev_half_ : v_half_;
  for (std::size_t i = 0; i < u.size(); ++i) u[i] = u_[i] - dt_prev_ * v[i];
  return u;
}

}  // namespace tactus::solver
