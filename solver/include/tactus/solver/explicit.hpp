#pragma once
// Explicit central-difference integration of M a + A v + f_int = f_ext + R (paper eqs. 33, 35),
// in the half-step velocity form
//   v^{n+1/2} = [(1 - alpha dtbar/2) v^{n-1/2} + dtbar M^{-1} (f_ext^n - f_int^n)] / (1 + alpha dtbar/2),
//   u^{n+1}   = u^n + dt^{n+1/2} v^{n+1/2},   dtbar = (dt^{n-1/2} + dt^{n+1/2}) / 2,
// which equals eq. 35 for a constant step and allows the step to follow the stable limit as the
// body deforms. The contract of one step is split in two so that the whole state at t^n
// (u^n, v^n = (v^{n-1/2} + v^{n+1/2})/2, energies) is visible to outputs between them:
//   advance_velocity(): needs u^n and the stress pass at u^n; gives v^{n+1/2} and energies at t^n.
//   advance_position(): gives u^{n+1}, t^{n+1} and the stress pass at u^{n+1}.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "tactus/solver/contact.hpp"
#include "tactus/solver/energy.hpp"
#include "tactus/solver/grip_regions.hpp"
#include "tactus/solver/internal_force.hpp"
#include "tactus/solver/joint_drive.hpp"
#include "tactus/solver/mass_scaling.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/relaxation.hpp"
#include "tactus/solver/rigid.hpp"
#include "tactus/solver/run_settings.hpp"
#include "tactus/solver/stress_pass_engine.hpp"
#include "tactus/solver/thread_tuner.hpp"

namespace tactus {
class StateArchive;
}

namespace tactus::solver {

class ExplicitSolver {
 public:
  // Performs the initial stress pass and chooses the step. Throws InputError when the user's
  // time_step exceeds the stable limit without force_time_step or the run or its output times are
  // closer than half a step, NumericalError when the initial configuration is inverted.
  // on_ranks: the stress pass spread over processes (RankStressPass, stress_pass_engine.hpp), which
  // then takes every pass; nullptr: this process's own (OneProcessStressPass).
  ExplicitSolver(const Model& model, const RunSpec& run, const DampingSpec& damping, StressPassEngine* on_ranks = nullptr);
  ~ExplicitSolver();

  void advance_velocity();
  void advance_position();

  double time() const { return time_; }
  std::size_t step_index() const { return step_; }
  double time_step() const { return dt_next_; }  // dt^{n+1/2}
  double last_step() const { return dt_prev_; }  // dt^{n-1/2}: the step that reached t^n
  // The output times the run lands on exactly (schedule.hpp), ending with end_time.
  const std::vector<double>& schedule() const { return schedule_; }
  // True when t^n is exactly the end time.
  bool finished() const { return time_ == run_.end_time; }
  // t^n landed on a scheduled output time (after advance_velocity): a state is due. The same on
  // every rank, which all take part in its cell records.
  bool at_output_time() const { return next_target_ > 0 && time_ == schedule_[next_target_ - 1]; }
  // The state files' cell records at u (StressPassEngine::cell_records; on ranks collective,
  // handed to sink on rank 0 only).
  void cell_records(const std::vector<double>& u, const std::vector<double>& v, const CellSink& sink) {
    passes_->cell_records(u.data(), v.data(), sink);
  }
  // Smallest ratio of a step taken to the nominal step at that time (>= 0.5 by construction).
  double min_step_ratio() const { return min_step_ratio_; }
  double initial_critical_step() const { return initial_critical_; }
  double critical_step() const { return pass_.critical_step; }
  std::size_t limiting_element() const { return pass_.limiting_element; }
  const StressPassResult& stress_pass() const { return pass_; }
  const Energies& energies() const { return audit_.energy; }
  const std::vector<double>& displacement() const { return u_; }
  std::vector<double> velocity_at_step() const;  // v^n (after advance_velocity)
  const std::vector<double>& half_step_velocity() const { return v_half_; }
  const std::vector<double>& internal_force() const { return f_; }  // on the nodes at t^n (minus the tets' internal force vector)
  // u^{n-1} = u^n - dt^{n-1/2} v^{n-1/2}: the last good state when step n fails.
  std::vector<double> previous_displacement() const;
  const Model& model() const { return model_; }
  std::size_t memory_bytes() const;  // integrator state + per-thread force buffers (not the model)
  int threads() const { return max_threads_; }
  // The automatic thread count's probes (thread_tuner.hpp): how many, and how many chose one thread.
  // The stress passes' and the contact sweep's tuners apart.
  const ThreadTuner& thread_tuner() const { return tuner_; }
  const ThreadTuner& contact_thread_tuner() const { return contact_tuner_; }
  // Contact at t^n (after advance_velocity): candidates with their reactions, and the step's report.
  const ContactSolver& contact() const { return contact_; }
  const ContactStepReport& contact_report() const { return contact_report_; }
  // The supports' reactions at t^n (after advance_velocity), one force and moment per boundary.
  const Reactions& reactions() const { return reactions_; }
  // Wall time spent so far in the stress passes and in contact (detection + Uzawa, outside the passes), s.
  double stress_seconds() const { return stress_seconds_; }
  double contact_seconds() const { return contact_seconds_; }
  // Of stress_seconds(): the next steps' contact detection, run on one thread during the passes.
  double detection_ahead_seconds() const { return detection_ahead_seconds_; }
  // Over ranks with owned-node stepping (stress_pass_engine.hpp), each process integrates only
  // the nodes it owns and those every process integrates (contact, rigid, supported, loaded), so
  // its arrays hold other nodes only where it reads them. gather_state (collective; a no-op
  // otherwise) brings every node's u and half-step velocities to every process: advance_velocity
  // calls it at each scheduled output time and when the run has relaxed, and a run that fails
  // calls it before writing the last good state.
  bool owned_node_stepping() const { return owned_stepping_; }
  void gather_state();
  // Checks energy blow-up / NaN at t^n; throws NumericalError naming step and time.
  void check_energy() const;
  // What limits the stable step, as the log prints it: "limited by tet 65 of body 'cube' (group
  // 'body', material 'rubber'), critical step 0.000277778 s", or the nodal bound's node and the
  // element estimate beside it.
  std::string describe_step_limit() const;
  // For a tet that inverts or collapses the step: the two rigid pieces nearest it (bones, a rigid
  // handle) with their distances, and the joint between them when a skeleton joins them: "; it
  // lies between bone 'middle_phalanx_index' of body 'hand' (0.3 mm) and body 'handle' (0.5 mm):
  // tissue crushed between two rigid bodies". Empty without rigid pieces.
  std::string describe_rigid_neighbours(std::size_t element) const;
  // Mass scaling (run.minimum_time_step > 0): mass added so far per body (model.bodies order), kg,
  // each body's own mass, and the momentum the added mass brought (dm v when it was added).
  bool mass_scaling() const { return masses_.on(); }
  const std::vector<double>& added_mass() const { return masses_.added_to_body; }
  const std::vector<double>& body_mass() const { return masses_.body_mass; }
  const Vec3& added_momentum() const { return masses_.added_momentum; }
  const std::vector<double>& nodal_mass() const { return masses_.mass; }  // the model's plus the added, per node
  // Rigid bodies (rigid.hpp): centre and rotation at t^n, momenta at t^{n+1/2} after advance_velocity.
  const std::vector<RigidBody>& rigid_bodies() const { return rigid_.bodies(); }
  // The seam for joint-driven motion (rigid.hpp): rigid piece k moves as `motion` says.
  void prescribe_rigid_motion(std::size_t piece, const RigidMotion& motion) { rigid_.prescribe(piece, motion); }
  // Dynamic relaxation ([damping] adaptive, residual_tolerance; relaxation.hpp): the damping of
  // the next step, the out-of-balance force, and whether the run has relaxed (it then stops).
  const Relaxation& relaxation() const { return relaxation_; }
  bool relaxed() const { return relaxation_.relaxed(); }
  // The joint drive ([skeleton], [[joint]], [grasp]; joint_drive.hpp), or nullptr.
  const JointDrive* joint_drive() const { return drive_.get(); }
  // The grasp's per-region sums (grip_regions.hpp), or none; sum_grip_regions refreshes them from
  // the last contact step (the outputs call it: nothing is summed per step otherwise).
  const GripRegions* grip_regions() const { return regions_.get(); }
  void sum_grip_regions() {
    if (regions_) regions_->sum(contact_);
  }

  // Saves (or, loading, restores) everything the next step reads: the state at t^n between
  // advance_position() and advance_velocity() - u^n, v^{n-1/2}, the forces and stress pass at u^n,
  // the step sequence, the pending energy halves, the added masses, the loading and the contact
  // solver's warm starts and searches (checkpoint.cpp). A solver built from the same model and run
  // settings and then loaded continues bit for bit as the one that saved.
  void checkpoint(StateArchive& archive);
  // Loading: refuses (InputError naming the checkpoint and the array) a restored state this model
  // cannot step from: non-finite or negative values, times outside the run, displacements whose
  // recomputed strain energy is not the stored one; then the energy check.
  void validate_restored(const StateArchive& archive);

 private:
  // detect_ahead: the next step's contact detection runs on one thread during the pass (it reads
  // the same u), off the step's critical path.
  void stress_pass(bool detect_ahead = false);
  // Mass scaling after a stress pass (mass_scaling.hpp); stops the run (a NumericalError naming
  // the body) when a body's added mass exceeds run.added_mass_limit.
  void scale_mass();
  // The constructor's refusals: a user time_step above the stable limit without force_time_step,
  // output times (or the run) shorter than half a step.
  void check_user_step();
  void check_schedule() const;
  void choose_step();  // sets dt_next_ and whether it lands on the next scheduled time
  ExternalForces external_forces() const {
    return {gravity_force_.data(), gravity_factor_, pressure_force_.empty() ? nullptr : pressure_force_.data()};
  }
  // Loading at t^n for the step to t_next (loading.cpp): the prescribed velocities of the driven
  // dofs, the gravity factor and the follower pressures on the current surface.
  void init_loading();  // the lists of constrained and driven dofs, the velocities at t = 0
  void apply_loading(double t_next, double dt);
  // Sums support_force_ per boundary into reactions_, with the moments about their points (loading.cpp).
  void accumulate_reactions();
  RelaxedDofs relaxed_dofs() const { return {masses_.mass.data(), model_.constrained.data(), rigid_.piece_of_node()}; }

  // Owned-node stepping when the engine is over ranks and the run allows it (constructor).
  void choose_stepping();
  // The free update and the position update over the dofs this process integrates.
  template <class Update>
  void for_integrated_dofs(Update&& update);
  // The threads of the passes and the nodal loops now.
  int pass_threads() const { return passes_->threads(); }

  const Model& model_;
  RunSpec run_;
  DampingSpec damping_;
  std::unique_ptr<StressPassEngine> own_passes_;  // this process's, when no engine over ranks is given
  StressPassEngine* passes_;                      // the one that computes them
  StressPassResult pass_;
  std::vector<double> u_, v_half_, v_prev_half_, f_;
  MassScaling masses_;  // the masses the run integrates with, and what mass scaling added
  int max_threads_;
  ThreadTuner tuner_;                  // run.threads = 0: one thread or all, whichever steps faster now (all but the contact sweep)
  ThreadTuner contact_tuner_;          // the same for the contact sweep, timed apart
  double step_seconds_ = 0;            // wall time of the step in progress (both halves)
  std::vector<double> gravity_force_;  // m g per dof (before the ramp)
  double gravity_factor_ = 1;
  std::vector<double> prescribed_v_;                     // per dof: the velocity a constrained dof takes over the step
  std::vector<std::int32_t> constrained_dofs_;           // every constrained dof, for the reactions
  std::vector<std::int32_t> driven_dofs_;                // those whose velocity changes in time (curve or displacement)
  std::vector<double> pressure_force_;                   // follower pressure forces at t^n (empty without [[load]])
  std::vector<double> support_force_;                    // per constrained dof (constrained_dofs_ order), at t^n
  std::vector<double> curve_at_next_, curve_increment_;  // per curve, this step: C(t^{n+1}), I(t^{n+1}) - I(t^n)
  Reactions reactions_;
  ContactSolver contact_;
  ContactStepReport contact_report_;
  double stress_seconds_ = 0, contact_seconds_ = 0;
  double detection_ahead_seconds_ = 0;  // inside stress_seconds_: contact detection run during the stress passes
  double time_ = 0, dt_prev_ = 0, dt_next_ = 0, user_dt_ = 0;
  std::vector<double> schedule_;
  std::size_t next_target_ = 0;  // first scheduled time > time_
  bool next_lands_ = false;
  double nominal_next_ = 0, min_step_ratio_ = 1, initial_critical_ = 0;
  std::size_t step_ = 0;
  bool velocity_advanced_ = false;
  bool owned_stepping_ = false;
  EnergyAudit audit_;                  // energies at t^n and the work halves carried to the next step (energy.hpp)
  RigidBodies rigid_;                  // the rigid pieces' state and their kick, drift and placement (rigid.hpp)
  std::unique_ptr<JointDrive> drive_;  // the bones' motion by their joints (joint_drive.hpp), or none
  Relaxation relaxation_;              // adaptive damping and the stop on the residual (relaxation.hpp)
  std::unique_ptr<GripRegions> regions_;
};

}  // namespace tactus::solver
