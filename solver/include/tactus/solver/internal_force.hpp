#pragma once
// The stress pass: one loop over all tets computing the internal (and viscous) nodal forces,
// the strain energy, the smallest Jacobian and the element stable step, in the same pass
// (Laghos' qdata.dt_est idea). Race-free assembly: each thread scatters into its own force
// array; the arrays are summed per node afterwards.
#include <cstddef>
#include <vector>

#include "tactus/solver/model.hpp"

namespace tactus::solver {

// Gradient of a nodal vector field over a one-point tet: sum_a w_a (x) grad N_a, written with the
// differences to node 0 (grad N_0 = -sum of the others). conn: the tet's 4 nodes; grad: its 9
// stored reference gradients. Gives F - I from displacements and Fdot from velocities.
[[gnu::always_inline]] inline Mat3 nodal_gradient(const double* __restrict field, const std::int32_t* conn, const double* __restrict grad) {
  const double* w0 = field + 3 * static_cast<std::size_t>(conn[0]);
  const double* w1 = field + 3 * static_cast<std::size_t>(conn[1]);
  const double* w2 = field + 3 * static_cast<std::size_t>(conn[2]);
  const double* w3 = field + 3 * static_cast<std::size_t>(conn[3]);
  Mat3 G;
  for (int i = 0; i < 3; ++i) {
    const double d1 = w1[i] - w0[i], d2 = w2[i] - w0[i], d3 = w3[i] - w0[i];
    for (int j = 0; j < 3; ++j) G(i, j) = d1 * grad[j] + d2 * grad[3 + j] + d3 * grad[6 + j];
  }
  return G;
}

struct StressPassResult {
  double strain_energy = 0;  // sum_e V_e W(F_e)
  double viscous_power = 0;  // sum_e V_e P_visc : Fdot (>= 0), Rayleigh beta part
  double critical_step = 0;  // min_e dt_e (no safety factor)
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
