#include "tactus/solver/relaxation.hpp"

#include <algorithm>
#include <cmath>

#include "tactus/core/state_file.hpp"
#include "tactus/solver/energy.hpp"
#include "tactus/solver/joint_drive.hpp"

namespace tactus::solver {

Relaxation::Relaxation(const DampingSpec& spec, std::size_t ndof) : spec_(spec), alpha_(spec.alpha), ndof_(ndof) {
  if (spec_.adaptive) force_before_.assign(ndof, 0.0);
}

void Relaxation::before_pass(const std::vector<double>& force) {
  if (spec_.adaptive) std::copy(force.begin(), force.end(), force_before_.begin());
}

// The sums run over fixed chunks of dofs, each chunk in dof order, the chunks' sums in chunk order:
// the same bits for any thread count (a restart and the determinism tests compare runs bit for
// bit) and, each chunk summed by one rank, for any rank count.
template <class Term>
std::array<double, 2> Relaxation::chunked_sums(Term&& term) {
  return sum_in_chunks<2>(ndof_, share_, chunks_, 1, {0, 0}, [&](std::size_t begin, std::size_t end) {
    double a = 0, b = 0;
    for (std::size_t i = begin; i < end; ++i) term(i, a, b);
    return std::array<double, 2>{a, b};
  });
}

void Relaxation::after_pass(const std::vector<double>& force, const double* v, double dt, const RelaxedDofs& dofs) {
  if (!spec_.adaptive || !(dt > 0)) return;
  // -(df . v) / dt and v . M v
  const auto [stiffness, inertia] = chunked_sums([&](std::size_t i, double& stiff, double& inert) {
    if (!dofs.free(i)) return;
    stiff -= (force[i] - force_before_[i]) * v[i];  // the force array holds -f_int: a stiffening motion lowers it
    inert += dofs.mass[i / 3] * v[i] * v[i];
  });
  const double omega2 = inertia > 0 ? stiffness / (dt * inertia) : 0.0;
  omega_ = omega2 > 0 ? std::sqrt(omega2) : 0.0;
  alpha_ = std::min(std::max(spec_.alpha, 2 * omega_), 1 / dt);
}

void Relaxation::measure(const HalfStep& h, const double* v_old, const double* v_new, const double* force, const RelaxedDofs& dofs, double time,
                         const JointDrive* drive) {
  if (!(spec_.residual_tolerance > 0) || h.first) return;
  const auto [out_of_balance, internal] = chunked_sums([&](std::size_t i, double& out, double& in) {
    // The scale: the internal force on every dof, the supported and the bone-held ones too (on
    // the free dofs alone it vanishes with the residual at equilibrium wherever no load acts).
    in += force[i] * force[i];
    if (!dofs.free(i)) return;
    const double r = dofs.mass[i / 3] * (v_new[i] / h.c_plus - h.c_minus * v_old[i]) / h.dtbar;
    out += r * r;
  });
  residual_ = internal > 0 ? std::sqrt(out_of_balance / internal) : (out_of_balance > 0 ? 1.0 : 0.0);
  bool grip_held = true;
  if (drive && drive->grasp())
    grip_held = drive->grip_target() > 0 && std::abs(drive->grip_force() - drive->grip_target()) <= 0.01 * drive->grip_target();
  relaxed_ = time >= spec_.residual_after && residual_ <= spec_.residual_tolerance && grip_held;
}

// The forces before a pass are scratch: a checkpoint falls between steps, after after_pass has
// used them and before the next before_pass overwrites them, so only the damping and the
// reported figures are state.
void Relaxation::checkpoint(StateArchive& a) {
  a.io("relaxation.alpha", alpha_);
  a.io("relaxation.omega", omega_);
  a.io("relaxation.residual", residual_);
}

}  // namespace tactus::solver
