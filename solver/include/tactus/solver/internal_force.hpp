#pragma once
// The stress pass: one loop over all tets computing the internal (and viscous) nodal forces,
// the strain energy, the smallest Jacobian and the element stable step, in the same pass
// (Laghos' qdata.dt_est idea). Race-free assembly: each thread scatters into its own force
// array; the arrays are summed per node afterwards.
#include <cstddef>
#include <vector>

#include "tactus/solver/model.hpp"

namespace tactus::solver {

struct StressPassResult {
  double strain_energy = 0;    // sum_e V_e W(F_e)
  double viscous_power = 0;    // sum_e V_e P_visc : Fdot (>= 0), Rayleigh beta part
  double critical_step = 0;    // min_e dt_e (no safety factor)
  std::size_t limiting_element = 0;
  double min_jacobian = 0;
  std::size_t min_jacobian_element = 0;
};

class InternalForces {
 public:
  // beta: Rayleigh stiffness-proportional damping (s); threads <= 0: all cores, at most one per ~4000 tets.
  InternalForces(const Model& model, double beta, int threads);
  // f_out (3 per node) = -(f_int + f_visc) at displacement u and velocity v (v used if beta > 0).
  StressPassResult compute(const double* u, const double* v, double* f_out);
  int threads() const { return threads_; }
  std::size_t memory_bytes() const;

 private:
  const Model& model_;
  double beta_;
  int threads_;
  std::vector<std::vector<double>> thread_forces_;  // threads-1 extra buffers (thread 0 writes f_out)
};

}  // namespace tactus::solver
