#pragma once
// The energy audit of the explicit integrator: kinetic, internal, external, damping and contact
// energies at t^n, with the work terms integrated by Belytschko's trapezoid rule (each step's
// F^n . du^{n-1/2} closes the step before, and F^n . du^{n+1/2} is carried to the next), so that
// their balance is zero for an exact integrator and an unstable step shows as a growing error.
// The sums run over fixed chunks of dofs, added in chunk order: the same bits for any number of
// threads (an OpenMP reduction adds in an order that depends on it).
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace tactus::solver {

class MassScaling;
class RigidBodies;
struct ContactStepReport;
struct StressPassResult;

struct Energies {
  double kinetic = 0, internal = 0, damping_work = 0, external_work = 0, initial = 0;
  // Energy taken out by the contact reactions (minus their work on the relative motion): normal
  // (velocity-level impact losses) and frictional (Coulomb sliding) parts.
  double contact_normal_work = 0, contact_friction_work = 0;
  double peak = 0;  // largest kinetic + internal seen, for relative errors
  // Mass scaling: the kinetic energy the added mass brought (1/2 dm v^2 when it was added).
  double added_mass_kinetic = 0;
  double contact_work() const { return contact_normal_work + contact_friction_work; }
  // kinetic + internal + damping work + contact work - external work - initial - added mass's
  // kinetic energy: zero for an exact integrator.
  double balance_error() const { return kinetic + internal + damping_work + contact_work() - external_work - initial - added_mass_kinetic; }
  double scale() const;
};

// One step of the half-step velocity update (paper eq. 35 with mass-proportional damping alpha),
// from t^{n-1/2} to t^{n+1/2}: v^{n+1/2} = [(1 - alpha dtbar/2) v^{n-1/2} + dtbar M^-1 F^n] /
// (1 + alpha dtbar/2), dtbar = (dt^{n-1/2} + dt^{n+1/2}) / 2.
struct HalfStep {
  double dt = 0, dt_prev = 0, dtbar = 0, alpha = 0, c_minus = 1, c_plus = 1;
  bool first = false;  // step 0: v^n is v^{-1/2} itself (the initial velocity)
  HalfStep(double dt_prev_, double dt_, double alpha_, bool first_)
      : dt(dt_), dt_prev(dt_prev_), dtbar(0.5 * (dt_prev_ + dt_)), alpha(alpha_), first(first_) {
    c_minus = 1.0 - 0.5 * alpha * dtbar, c_plus = 1.0 / (1.0 + 0.5 * alpha * dtbar);
  }
  // v^{n+1/2} of a dof without contact or support, from v^{n-1/2}, f_ext - f_int (f_int stored with
  // its sign: the internal force's negative) and 1/m.
  double free_velocity(double v_old, double f_ext, double f_int, double inverse_mass) const {
    return (c_minus * v_old + dtbar * (f_ext + f_int) * inverse_mass) * c_plus;
  }
};

// The external forces at t^n per dof: gravity (on the physical mass, times its ramp) and the
// follower pressures (nullptr: none).
struct ExternalForces {
  const double* gravity = nullptr;
  double gravity_factor = 1;
  const double* pressure = nullptr;
  double at(std::size_t dof) const { return gravity_factor * gravity[dof] + (pressure ? pressure[dof] : 0.0); }
};

// Sums over the dofs taken in fixed chunks of kSumChunkDofs dofs, each chunk's partial sum added
// in chunk order: the same bits at any thread count, and at any rank count when each chunk is
// summed by one process and the partial sums gathered (owned-node stepping over ranks,
// stress_pass_engine.hpp): a sum then computes only the chunks marked in `summed_here` (1 each;
// null: all) and calls gather(context, partial sums, width) for the others'.
inline constexpr std::size_t kSumChunkDofs = 4096;
struct ChunkShare {
  const char* summed_here = nullptr;
  void (*gather)(void* context, double* chunks, std::size_t width) = nullptr;
  void* context = nullptr;
  bool sums(std::size_t chunk) const { return !summed_here || summed_here[chunk]; }
};

// The chunked sums of `ndof` dofs: chunk_sum(begin, end) gives a chunk's W partial sums, for the
// chunks this process sums (`threads` at once; `chunks` keeps them, one per chunk), the others'
// gathered through `share`; returns `start` plus every chunk's sums, added in chunk order.
template <std::size_t W, class ChunkSum>
std::array<double, W> sum_in_chunks(std::size_t ndof, const ChunkShare& share, std::vector<std::array<double, W>>& chunks, int threads,
                                    std::array<double, W> start, ChunkSum&& chunk_sum) {
  const std::size_t n = (ndof + kSumChunkDofs - 1) / kSumChunkDofs;
  chunks.resize(n);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::size_t k = 0; k < n; ++k)
    if (share.sums(k)) chunks[k] = chunk_sum(k * kSumChunkDofs, std::min(ndof, (k + 1) * kSumChunkDofs));
  if (share.gather) share.gather(share.context, chunks.data()->data(), W);
  for (const auto& c : chunks)
    for (std::size_t j = 0; j < W; ++j) start[j] += c[j];
  return start;
}

class EnergyAudit {
 public:
  // The energies at t = 0: the physical kinetic energy (mass added at t = 0 is booked as added,
  // with its momentum) and the strain energy of the initial pass.
  void start(const double* v, MassScaling& masses, const double* model_mass, const RigidBodies& rigid, double strain_energy);
  // The energies at t^n after the velocity update of `step`: v_old = v^{n-1/2}, v_new = v^{n+1/2},
  // f_int the internal forces at t^n; the supports' reactions are what the update added to the
  // prescribed dofs. Rigid bodies add their own kinetic energy and work, the contact sweep its
  // report's work terms, the stress pass its viscous power.
  void close_step(const HalfStep& step, const ExternalForces& external, const double* v_old, const double* v_new, const double* f_int,
                  MassScaling& masses, const std::uint8_t* constrained, const RigidBodies& rigid, const ContactStepReport& contact,
                  const StressPassResult& pass, int threads);

  // Owned-node stepping over ranks: close_step sums only the chunks this process sums and gathers
  // the others' partial sums (ChunkShare).
  void share_chunks(ChunkShare share) { share_ = share; }

  Energies energy;
  // The halves of the trapezoid rule carried to the next step: F^n . du^{n+1/2} per kind.
  double pending_external = 0, pending_damping = 0, pending_contact_normal = 0, pending_contact_friction = 0;

 private:
  std::vector<std::array<double, 5>> chunks_;  // kinetic, ext_back, ext_fwd, damp_back, damp_fwd
  ChunkShare share_;
};

}  // namespace tactus::solver
