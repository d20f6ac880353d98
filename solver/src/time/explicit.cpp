#include "tactus/solver/explicit.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <iomanip>
#include <limits>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/solver/schedule.hpp"

namespace tactus::solver {

ExplicitSolver::ExplicitSolver(const Model& model, const RunSpec& run, const DampingSpec& damping, StressPassEngine* on_ranks)
    : model_(model),
      run_(run),
      damping_(damping),
      own_passes_(on_ranks ? nullptr : std::make_unique<OneProcessStressPass>(model, damping.beta, run.threads)),
      passes_(on_ranks ? on_ranks : own_passes_.get()),
      masses_(model, run.minimum_time_step),
      max_threads_(pass_threads()),
      tuner_(max_threads_, run.threads == 0),
      contact_tuner_(max_threads_, run.threads == 0),
      contact_(model),
      relaxation_(damping, 3 * model.num_nodes) {
  const std::size_t ndof = 3 * model.num_nodes;
  u_.assign(ndof, 0.0);
  f_.assign(ndof, 0.0);
  v_half_ = model.initial_velocity;
  init_loading();
  for (std::size_t i = 0; i < ndof; ++i)
    if (model.constrained[i]) v_half_[i] = prescribed_v_[i];
  v_prev_half_ = v_half_;
  gravity_force_.resize(ndof);
  for (std::size_t i = 0; i < ndof; ++i) gravity_force_[i] = model.mass[i / 3] * run.gravity[i % 3];  // on the physical mass, also under mass scaling
  if (mass_scaling()) passes_->enable_mass_scaling();
  rigid_.init(model_, v_half_.data(), v_prev_half_.data(), masses_.contact_inverse_mass.data());
  if (model.joint_drive.on()) drive_ = std::make_unique<JointDrive>(model_, rigid_);
  if (drive_ && drive_->grasp()) regions_ = std::make_unique<GripRegions>(model_, rigid_, *drive_, contact_);
  contact_.set_threads(pass_threads());
  choose_stepping();
  if (!contact_.empty()) contact_.check_initial_overlap(u_.data());
  schedule_ = output_schedule(run);
  while (next_target_ < schedule_.size() && schedule_[next_target_] <= 0) ++next_target_;
  stress_pass();
  initial_critical_ = pass_.critical_step;
  contact_.set_pressure_window(std::max(model.contact_settings.pressure_window, 10 * initial_critical_));
  audit_.start(v_half_.data(), masses_, model.mass.data(), rigid_, pass_.strain_energy);
  check_user_step();
  check_schedule();
  choose_step();
}

void ExplicitSolver::check_user_step() {
  if (run_.time_step > 0) {
    const double limit = pass_.critical_step;
    if (run_.time_step > limit && !run_.force_time_step) {
      std::ostringstream o;
      o << "a step <= the stable limit " << limit << " s (" << describe_step_limit()
        << "); lower it, remove it for the automatic step, or set run.force_time_step = true";
      std::ostringstream f;
      f << run_.time_step << " s";
      throw InputError(model_.source, "run.time_step", o.str(), f.str());
    }
    user_dt_ = run_.time_step;
  }
  if (!(user_dt_ > 0) && !std::isfinite(pass_.critical_step))
    throw InputError(model_.source, "run.time_step", "a time step (every tet is rigid: no stable limit to take it from)", "none");
}

void ExplicitSolver::check_schedule() const {
  // Scheduled times closer than half a step apart cannot be landed on without tiny steps (each
  // state would repeat the one before): refused, naming them.
  const double nominal = user_dt_ > 0 ? user_dt_ : run_.time_step_safety * pass_.critical_step;
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
      throw InputError(model_.source, run_.output_interval > 0 ? "run.output_interval" : "run.output_times", o.str(), f.str());
    }
    before = t;
  }
}

ExplicitSolver::~ExplicitSolver() = default;

// Over ranks every process integrates its own nodes and those whose forces and motion the whole
// model's parts share (contact, rigid, supported, loaded): every per-step sum over the dofs is then
// either chunked (the energy audit, the relaxation: ChunkShare) or over nodes every process holds
// (the supports' reactions, the rigid bodies, the contact sweep), or gathers the few nodes it reads
// (mass scaling's newly raised nodes).
void ExplicitSolver::choose_stepping() {
  if (passes_->ranks() < 2) return;
  std::vector<char> everywhere(model_.num_nodes, 0);
  for (std::int32_t n : contact_.contact_nodes()) everywhere[static_cast<std::size_t>(n)] = 1;
  for (std::size_t n = 0; n < model_.num_nodes; ++n)
    if (rigid_.holds(n) || model_.constrained[3 * n] || model_.constrained[3 * n + 1] || model_.constrained[3 * n + 2]) everywhere[n] = 1;
  for (const PressureLoad& load : model_.pressure_loads)
    for (std::int32_t n : load.triangles) everywhere[static_cast<std::size_t>(n)] = 1;
  passes_->step_owned_nodes(everywhere, kSumChunkDofs);
  const ChunkShare share{
      passes_->sum_chunks_summed_here(),
      [](void* engine, double* chunks, std::size_t width) { static_cast<StressPassEngine*>(engine)->gather_sum_chunks(chunks, width); }, passes_};
  audit_.share_chunks(share);
  relaxation_.share_chunks(share);
  owned_stepping_ = true;
}

void ExplicitSolver::gather_state() {
  if (owned_stepping_) passes_->gather_nodes({u_.data(), v_half_.data(), v_prev_half_.data()});
}

template <class Update>
void ExplicitSolver::for_integrated_dofs(Update&& update) {
  const std::vector<std::uint32_t>& dofs = passes_->integrated_dofs();
  if (dofs.empty()) {
    const std::size_t ndof = 3 * model_.num_nodes;
#pragma omp parallel for num_threads(pass_threads()) schedule(static)
    for (std::size_t i = 0; i < ndof; ++i) update(i);
  } else {
    const std::uint32_t* list = dofs.data();
    const std::size_t n = dofs.size();
#pragma omp parallel for num_threads(pass_threads()) schedule(static)
    for (std::size_t k = 0; k < n; ++k) update(static_cast<std::size_t>(list[k]));
  }
}

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
  const double* bound_masses = run_.step_estimate == StepEstimate::nodal ? masses_.mass.data() : nullptr;  // the masses the run integrates with
  passes_->set_nodal_step_bound(bound_masses);
  pass_ = passes_->compute_everywhere(u_.data(), v_half_.data(), f_.data(), side);
  stress_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  detection_ahead_seconds_ += ahead.seconds;
  if (ahead.error) std::rethrow_exception(ahead.error);
  if (!(pass_.min_jacobian > 0)) {
    gather_state();  // every rank fails here alike: the message reads the tet's nodes wherever they are integrated
    std::ostringstream o;
    o << "inverted element at step " << step_ << ", t = " << time_ << " s: " << model_.describe_element(pass_.min_jacobian_element)
      << " has J = " << pass_.min_jacobian << " (the time step may be too large, or the loading too severe for this mesh)"
      << describe_rigid_neighbours(pass_.min_jacobian_element);
    throw NumericalError(o.str());
  }
  if (!std::isfinite(pass_.strain_energy)) {
    std::ostringstream o;
    o << "non-finite strain energy at step " << step_ << ", t = " << time_ << " s";
    throw NumericalError(o.str());
  }
  if (mass_scaling() && pass_.critical_step < run_.minimum_time_step) scale_mass();
  if (owned_stepping_ && relaxation_.reads_forces()) passes_->share_ghosts(f_.data());  // its chunks' nodes
}

void ExplicitSolver::scale_mass() {
  masses_.scale(passes_->raise_to_floor(masses_.floor_squared()), rigid_);
  MassScaling::take_scaled_step(pass_, passes_->smallest_scaled_step(damping_.beta));
  const std::ptrdiff_t over = masses_.body_over(run_.added_mass_limit);
  if (over < 0) return;
  gather_state();  // (as for an inverted tet)
  const auto b = static_cast<std::size_t>(over);
  const double added = masses_.added_to_body[b], mass = masses_.body_mass[b];
  std::ostringstream o;
  o << "mass scaling has added " << added << " kg to body '" << model_.bodies[b].name << "' by step " << step_ << ", t = " << time_
    << " s: " << 100 * added / mass << " % of its " << mass << " kg, above run.added_mass_limit = " << 100 * run_.added_mass_limit
    << " %, to keep the step at run.minimum_time_step = " << run_.minimum_time_step << " s (" << describe_step_limit()
    << "); lower minimum_time_step or raise added_mass_limit" << describe_rigid_neighbours(pass_.limiting_element);
  throw NumericalError(o.str());
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

std::string ExplicitSolver::describe_rigid_neighbours(std::size_t e) const {
  const std::vector<RigidBody>& pieces = rigid_.bodies();
  if (pieces.size() < 2 || e >= model_.num_elements) return "";
  Vec3d c = Vec3d::Zero();
  for (const std::int32_t node : passes_->tet_nodes(e)) {  // (on ranks collective, as the message is)
    const auto a = static_cast<std::size_t>(node);
    c += 0.25 * (Vec3d(&model_.X[3 * a]) + Vec3d(&u_[3 * a]));
  }
  std::vector<std::pair<double, std::size_t>> nearest;  // distance, piece
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    double d = 1e300;
    for (std::int32_t a : pieces[p].nodes) {
      const auto i = static_cast<std::size_t>(a);
      d = std::min(d, (Vec3d(&model_.X[3 * i]) + Vec3d(&u_[3 * i]) - c).norm());
    }
    nearest.emplace_back(d, p);
  }
  std::partial_sort(nearest.begin(), nearest.begin() + 2, nearest.end());
  // A piece by the skeleton bone the joint drive matched it to, else its volume group's name.
  auto bone = [&](std::size_t piece) {
    if (drive_)
      for (std::size_t b = 0; b < drive_->skeleton().bones.size(); ++b)
        for (std::size_t q : drive_->pieces(b))
          if (q == piece) return drive_->skeleton().bones[b].name;
    const RigidBody& r = pieces[piece];
    const BodyRange& body = model_.bodies[r.body];
    for (std::size_t g = body.group_begin; g < body.group_end; ++g)
      if (model_.input_mesh.groups[g].dim == 3 && model_.input_mesh.groups[g].tag == r.groups.front()) return model_.input_mesh.groups[g].name;
    return std::string();
  };
  std::ostringstream o;
  o << std::setprecision(3) << "; it lies between ";
  for (int k = 0; k < 2; ++k) {
    const RigidBody& r = pieces[nearest[static_cast<std::size_t>(k)].second];
    const bool one_piece = std::count_if(pieces.begin(), pieces.end(), [&](const RigidBody& q) { return q.body == r.body; }) == 1;
    o << (k ? " and " : "") << (one_piece ? "" : "bone '" + bone(nearest[static_cast<std::size_t>(k)].second) + "' of ") << "body '"
      << model_.bodies[r.body].name << "' (" << nearest[static_cast<std::size_t>(k)].first * 1e3 << " mm)";
  }
  const std::string a = bone(nearest[0].second), b = bone(nearest[1].second);
  if (drive_) {
    const std::vector<SkeletonJoint>& joints = drive_->skeleton().joints;
    for (std::size_t j = 0; j < joints.size(); ++j)
      if ((joints[j].proximal == a && joints[j].distal == b) || (joints[j].proximal == b && joints[j].distal == a)) {
        o << ", across the joint '" << joints[j].name << "' (flexed " << drive_->flexion_at_step()[j] * 180 / M_PI
          << " deg: an angle or torque beyond what the tissue there takes?)";
        return o.str();
      }
  }
  o << ": tissue crushed between two rigid bodies";
  return o.str();
}

// Paper eq. 35 in the half-step form (explicit.hpp): the free update from the forces at t^n, the
// rigid bodies' kick, the contact reactions' correction, the rigid bodies' drift, then the
// supports' reactions and the energy audit at t^n.
void ExplicitSolver::advance_velocity() {
  const auto started = std::chrono::steady_clock::now();
  // The stress passes and the contact sweep each take the thread count their own tuner found
  // faster: the sweep's many short parallel loops lose to one thread where the stress pass gains.
  if (const int n = tuner_.threads(); n != pass_threads()) passes_->set_threads(n);
  if (const int n = contact_tuner_.threads(); n != contact_.threads()) contact_.set_threads(n);
  double contact_seconds = 0;
  const HalfStep h(dt_prev_, dt_next_, relaxation_.alpha(), step_ == 0);  // [damping] alpha, or adaptive
  const double t_next = next_lands_ ? schedule_[next_target_] : time_ + h.dt;
  apply_loading(t_next, h.dt);
  v_prev_half_.swap(v_half_);
  const double* __restrict v_old_of = v_prev_half_.data();
  double* __restrict v_new_of = v_half_.data();
  const double* inverse_mass = masses_.inverse_mass.data();
  const ExternalForces external = external_forces();
  for_integrated_dofs([&](std::size_t i) {
    v_new_of[i] = model_.constrained[i] ? prescribed_v_[i] : h.free_velocity(v_old_of[i], external.at(i), f_[i], inverse_mass[i]);
  });
  if (!rigid_.empty()) {
    rigid_.sum_loads(model_, f_.data(), external, u_.data());
    // The joints set the bones' motion over the step from those loads (joint_drive.hpp).
    if (drive_) drive_->steer(model_, rigid_, contact_.pair_reports(), contact_.pairs(), time_, t_next, h.dt, h.dtbar, h.c_minus, h.c_plus);
    rigid_.kick(model_, u_.data(), time_, t_next, h.dt, h.dtbar, h.c_minus, h.c_plus);
  }
  // Contact reactions at t^n correct it (paper eq. 35 with R): dv = dtbar c_plus M^-1 R.
  if (!contact_.empty()) {
    const auto t0 = std::chrono::steady_clock::now();
    contact_report_ = contact_.correct_velocities(u_.data(), v_new_of, v_old_of, masses_.contact_inverse_mass.data(), h.dtbar * h.c_plus, h.dt,
                                                  dt_prev_, rigid_.contact_rows());
    contact_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    contact_seconds_ += contact_seconds;
    contact_tuner_.step_took(contact_seconds);
  }
  if (!rigid_.empty()) rigid_.drift(model_, u_.data(), h.dt, v_new_of);
  if (owned_stepping_) passes_->share_ghosts(v_new_of);  // the next pass's and the audit's nodes of other ranks
  // The supports' forces: R = m (v_new - v_free) / (dtbar c_plus), exactly what the update added.
  for (std::size_t k = 0; k < constrained_dofs_.size(); ++k) {
    const auto i = static_cast<std::size_t>(constrained_dofs_[k]);
    support_force_[k] =
        masses_.mass[i / 3] * (v_new_of[i] - h.free_velocity(v_old_of[i], external.at(i), f_[i], inverse_mass[i])) / (h.dtbar * h.c_plus);
  }
  accumulate_reactions();
  // The nodes whose mass was raised: their added kinetic energy is booked in node order.
  if (owned_stepping_ && masses_.on() && !masses_.raised_nodes().empty())
    passes_->gather_some_nodes(masses_.raised_nodes(), {v_prev_half_.data(), v_half_.data()});
  audit_.close_step(h, external, v_old_of, v_new_of, f_.data(), masses_, model_.constrained.data(), rigid_, contact_report_, pass_, pass_threads());
  if (drive_) drive_->observe(time_, audit_.energy.kinetic, audit_.energy.internal);
  relaxation_.measure(h, v_old_of, v_new_of, f_.data(), relaxed_dofs(), time_, drive_.get());
  velocity_advanced_ = true;
  // A scheduled output time (t^n landed on one), or the relaxed state that ends the run: the state
  // file needs every node.
  if (owned_stepping_ && (at_output_time() || relaxation_.relaxed())) gather_state();
  step_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count() - contact_seconds;
}

void ExplicitSolver::check_energy() const {
  const double err = audit_.energy.balance_error();
  std::ostringstream o;
  if (!std::isfinite(err) || !std::isfinite(audit_.energy.kinetic)) {
    o << "non-finite energy at step " << step_ << ", t = " << time_ << " s (NaN or overflow; " << describe_step_limit() << ")";
    throw NumericalError(o.str());
  }
  // Relative to the largest energy, from the tenth step on: a run starting at rest (under gravity
  // or a load ramp) has every energy O(dt^2) in its first steps, where the trapezoid rule's lag in
  // the work terms is of the same size, so their ratio says nothing (it stopped such runs at step
  // 1). An unstable step grows the energy by a factor per step and is still caught a few steps on.
  if (step_ >= 10 && std::abs(err) > run_.energy_tolerance * audit_.energy.scale()) {
    o << "energy blow-up at step " << step_ << ", t = " << time_ << " s: energy balance error " << err << " J is "
      << std::abs(err) / audit_.energy.scale() << " of the largest energy (tolerance run.energy_tolerance = " << run_.energy_tolerance
      << "); time step " << dt_next_ << " s vs " << describe_step_limit() << " - the step is above the stable limit or the model is unstable";
    throw NumericalError(o.str());
  }
}

void ExplicitSolver::advance_position() {
  const auto started = std::chrono::steady_clock::now();
  const double dt = dt_next_;
  for_integrated_dofs([&](std::size_t i) { u_[i] += dt * v_half_[i]; });
  rigid_.place(model_, u_.data());
  if (owned_stepping_) passes_->share_ghosts(u_.data());  // the pass reads its tets' nodes
  min_step_ratio_ = std::min(min_step_ratio_, dt / nominal_next_);
  if (next_lands_) {
    time_ = schedule_[next_target_++];  // exactly, not the sum of the steps
  } else {
    time_ += dt;
  }
  ++step_;
  dt_prev_ = dt;
  velocity_advanced_ = false;
  relaxation_.before_pass(f_);
  stress_pass(true);
  relaxation_.after_pass(f_, v_half_.data(), dt, relaxed_dofs());
  if (pass_.critical_step < 1e-3 * initial_critical_) {
    gather_state();  // (as for an inverted tet)
    std::ostringstream o;
    o << "the stable time step collapsed to " << pass_.critical_step << " s at step " << step_ << ", t = " << time_
      << " s, below 1e-3 of the initial " << initial_critical_ << " s (" << describe_step_limit()
      << "): " << model_.describe_element(pass_.limiting_element)
      << " is being crushed or its material stiffens without bound (fibres?); the run would not finish"
      << describe_rigid_neighbours(pass_.limiting_element);
    throw NumericalError(o.str());
  }
  choose_step();
  tuner_.step_took(step_seconds_ + std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
}

std::size_t ExplicitSolver::memory_bytes() const {
  std::size_t doubles = u_.capacity() + v_half_.capacity() + v_prev_half_.capacity() + f_.capacity() + masses_.inverse_mass.capacity() +
                        gravity_force_.capacity() + masses_.mass.capacity() + masses_.pending_added.capacity();
  return doubles * sizeof(double) + passes_->memory_bytes();
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
