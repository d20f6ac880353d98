#pragma once
// Quasi-static runs by dynamic relaxation ([damping] adaptive, residual_tolerance): the explicit
// integrator as an iterative solver of f_int = f_ext + R.
//   - Adaptive damping (Underwood's adaptive dynamic relaxation, in the form of Zhang & Yu's
//     velocity-based estimate): after each stress pass the Rayleigh quotient of the tangent
//     stiffness along the step's velocity, omega^2 = -(df . v) / (dt v . M v) with df the change of
//     the nodal force over the step, estimates the frequency of the motion that is left, which a
//     relaxing body concentrates in its lowest mode; the next step's mass-proportional damping is
//     alpha = 2 omega (critical damping of that mode), never below [damping] alpha and never
//     above 1 / dt. The integrator books it as any alpha (energy.hpp), so the energy audit still
//     closes.
//   - Convergence: after each velocity update, the out-of-balance force on the free deformable
//     dofs, r = m (v^{n+1/2} / c_plus - c_minus v^{n-1/2}) / dtbar (what the update applied besides
//     damping: external, internal and contact forces), against the internal force on all dofs
//     (the supports' and bones' reactions balance it there). The run stops once
//     |r| <= residual_tolerance |f_int| after residual_after (and, under a grasp, with the grip
//     within 1 % of its target).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "tactus/solver/energy.hpp"
#include "tactus/solver/run_settings.hpp"

namespace tactus {
class StateArchive;
}

namespace tactus::solver {

struct HalfStep;
class JointDrive;

// The dofs the relaxation measures: free (not prescribed) and not on a rigid piece.
struct RelaxedDofs {
  const double* mass = nullptr;               // per node, the masses the run integrates with
  const std::uint8_t* constrained = nullptr;  // per dof
  const std::int32_t* rigid_piece = nullptr;  // per node (-1: deformable), or nullptr
  bool free(std::size_t dof) const { return !constrained[dof] && (!rigid_piece || rigid_piece[dof / 3] == -1); }
};

class Relaxation {
 public:
  Relaxation(const DampingSpec& spec, std::size_t ndof);
  bool adaptive() const { return spec_.adaptive; }
  double alpha() const { return alpha_; }  // the next step's mass-proportional damping, 1/s
  double omega() const { return omega_; }  // the last estimate of the relaxing mode's frequency, rad/s
  // Before the stress pass to t^{n+1}: keeps the nodal forces at t^n.
  void before_pass(const std::vector<double>& force);
  // After it: the next alpha from the change of the forces over the step dt with velocity v.
  void after_pass(const std::vector<double>& force, const double* v, double dt, const RelaxedDofs& dofs);
  // After the velocity update at t^n: the relative out-of-balance force, and whether the run has relaxed.
  void measure(const HalfStep& h, const double* v_old, const double* v_new, const double* force, const RelaxedDofs& dofs, double time,
               const JointDrive* drive);
  double relative_residual() const { return residual_; }
  bool relaxed() const { return relaxed_; }
  void checkpoint(StateArchive& archive);
  // Its sums are over the dofs in fixed chunks (ChunkShare, energy.hpp); over ranks each process
  // sums its own chunks and gathers the others'.
  void share_chunks(ChunkShare share) { share_ = share; }
  // Whether the sums read the forces at every dof (adaptive damping or the residual's stop).
  bool reads_forces() const { return spec_.adaptive || spec_.residual_tolerance > 0; }

 private:
  // Two sums over the dofs, term(dof, a, b) adding to a and b, per chunk then in chunk order.
  template <class Term>
  std::array<double, 2> chunked_sums(Term&& term);
  ChunkShare share_;
  std::vector<std::array<double, 2>> chunks_;
  DampingSpec spec_;
  double alpha_, omega_ = 0, residual_ = -1;
  std::size_t ndof_;
  bool relaxed_ = false;
  std::vector<double> force_before_;  // scratch: the nodal forces at t^n during the pass to t^{n+1} (adaptive only)
};

}  // namespace tactus::solver
