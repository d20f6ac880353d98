#include "tactus/solver/energy.hpp"

#include <algorithm>
#include <cmath>

#include "tactus/solver/contact.hpp"
#include "tactus/solver/internal_force.hpp"
#include "tactus/solver/mass_scaling.hpp"
#include "tactus/solver/rigid.hpp"

namespace tactus::solver {

double Energies::scale() const { return std::max({std::abs(initial), peak, std::abs(external_work), std::abs(damping_work), 1e-300}); }

void EnergyAudit::start(const double* v, MassScaling& masses, const double* model_mass, const RigidBodies& rigid, double strain_energy) {
  const std::size_t ndof = 3 * masses.mass.size();
  double kinetic = rigid.kinetic_energy(true), added = 0;
  for (std::size_t i = 0; i < ndof; ++i) {
    if (rigid.holds(i / 3)) continue;
    kinetic += 0.5 * masses.mass[i / 3] * v[i] * v[i];
    added += 0.5 * (masses.mass[i / 3] - model_mass[i / 3]) * v[i] * v[i];
    masses.added_momentum[i % 3] += (masses.mass[i / 3] - model_mass[i / 3]) * v[i];
  }
  if (masses.on()) masses.forget_added();
  energy.kinetic = kinetic;
  energy.internal = strain_energy;
  energy.added_mass_kinetic = added;
  energy.initial = kinetic - added + strain_energy;
  energy.peak = energy.initial;
}

void EnergyAudit::close_step(const HalfStep& h, const ExternalForces& external, const double* __restrict v_old_of, const double* __restrict v_new_of,
                             const double* f_int, MassScaling& masses, const std::uint8_t* constrained, const RigidBodies& rigid,
                             const ContactStepReport& c, const StressPassResult& pass, int threads) {
  const std::size_t ndof = 3 * masses.mass.size();
  const double* __restrict mass_of = masses.mass.data();
  const double* inverse_mass = masses.inverse_mass.data();
  const std::int32_t* rigid_of = rigid.piece_of_node();
  if (masses.on()) masses.book_added(v_old_of, v_new_of, h.first, energy.added_mass_kinetic);
  // kinetic (from the rigid bodies'), ext_back, ext_fwd, damp_back, damp_fwd
  auto [kinetic, ext_back, ext_fwd, damp_back, damp_fwd] =
      sum_in_chunks<5>(ndof, share_, chunks_, threads, {rigid.kinetic_energy(h.first), 0, 0, 0, 0}, [&](std::size_t begin, std::size_t end) {
        std::array<double, 5> sum{};
        for (std::size_t i = begin; i < end; ++i) {
          // A rigid body's nodes: their kinetic energy and damping are the body's (below).
          const double m = rigid_of && rigid_of[i / 3] != -1 ? 0.0 : mass_of[i / 3];
          const double fext = external.at(i);
          const double v_old = v_old_of[i], v_new = v_new_of[i];
          double reaction = 0;
          if (constrained[i]) {  // the support force that holds the prescribed velocity: what the update added, dtbar c_plus R / m
            reaction = m * (v_new - h.free_velocity(v_old, fext, f_int[i], inverse_mass[i])) / (h.dtbar * h.c_plus);
          }
          const double v_n = h.first ? v_old : 0.5 * (v_old + v_new);
          sum[0] += 0.5 * m * v_n * v_n;
          // Work of F^n over du^{n-1/2} (closes step n-1) and du^{n+1/2} (carried to step n+1).
          const double F = fext + reaction;
          const double fdamp = h.alpha * m * v_n;
          sum[1] += F * h.dt_prev * v_old;
          sum[2] += F * h.dt * v_new;
          sum[3] += fdamp * h.dt_prev * v_old;
          sum[4] += fdamp * h.dt * v_new;
        }
        return sum;
      });
  rigid.add_work(h.alpha, h.dt_prev, h.dt, h.first, damp_back, damp_fwd, ext_back, ext_fwd);
  ext_back += c.support_work_back;
  ext_fwd += c.support_work_forward;
  energy.kinetic = kinetic;
  energy.internal = pass.strain_energy;
  energy.external_work += 0.5 * (pending_external + ext_back);
  energy.damping_work += 0.5 * (pending_damping + damp_back) + pass.viscous_power * h.dtbar;
  // The reactions' work on the relative motion, with the sign of energy taken out.
  energy.contact_normal_work -= 0.5 * (pending_contact_normal + c.normal_work_back);
  energy.contact_friction_work -= 0.5 * (pending_contact_friction + c.friction_work_back);
  pending_external = ext_fwd;
  pending_damping = damp_fwd;
  pending_contact_normal = c.normal_work_forward;
  pending_contact_friction = c.friction_work_forward;
  energy.peak = std::max(energy.peak, kinetic + pass.strain_energy);
}

}  // namespace tactus::solver
