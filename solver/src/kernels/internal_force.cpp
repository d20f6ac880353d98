// The stress pass over all blocks, in parallel: each thread takes a contiguous share of every
// block and calls the block's law kernel (kernels/element_loop.hpp, compiled per law) once for it.
#include "tactus/solver/internal_force.hpp"

#include "element_loop.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

namespace tactus::solver {

namespace {

// All cores unless OMP_NUM_THREADS says otherwise (not omp_get_max_threads(): libgmsh sets the
// OpenMP thread count to 1 when it initialises, which would silently serialise the solver), but
// at least ~4000 tets per thread: below that the two barriers per step cost more than they save,
// and on a loaded machine a spinning barrier can cost a whole scheduler slice per step.
int default_threads(std::size_t elements) {
  int n = omp_get_num_procs();
  if (const char* env = std::getenv("OMP_NUM_THREADS"))
    if (const int e = std::atoi(env); e > 0) n = e;
  const int useful = static_cast<int>(std::max<std::size_t>(1, elements / 4000));
  return std::min(n, useful);
}

}  // namespace

InternalForces::InternalForces(const Model& model, double beta, int threads)
    : model_(model), beta_(beta), threads_(threads > 0 ? threads : default_threads(model.num_elements)) {
  thread_forces_.resize(static_cast<std::size_t>(threads_ - 1));
  for (auto& buf : thread_forces_) buf.assign(3 * model.num_nodes, 0.0);
}

std::size_t InternalForces::memory_bytes() const {
  std::size_t b = 0;
  for (const auto& buf : thread_forces_) b += buf.capacity() * sizeof(double);
  return b;
}

StressPassResult InternalForces::compute(const double* u, const double* v, double* f_out) {
  const std::size_t ndof = 3 * model_.num_nodes;
  ThreadAccumulator total;
  const bool viscous = beta_ > 0;
#pragma omp parallel num_threads(threads_)
  {
    const int tid = omp_get_thread_num();
    const int nth = omp_get_num_threads();
    double* f = tid == 0 ? f_out : thread_forces_[static_cast<std::size_t>(tid - 1)].data();
    std::fill(f, f + ndof, 0.0);
    ThreadAccumulator acc;
    for (const auto& b : model_.blocks) {
      // Static contiguous split: each thread touches a compact set of nodes.
      const std::size_t n = b.end - b.begin;
      const std::size_t lo = b.begin + n * static_cast<std::size_t>(tid) / static_cast<std::size_t>(nth);
      const std::size_t hi = b.begin + n * static_cast<std::size_t>(tid + 1) / static_cast<std::size_t>(nth);
      const StressKernelArgs args{
          model_.conn.data(),   model_.grad.data(), model_.volume.data(), b.material.law(), b.data(), b.data_stride(), b.begin, lo, hi, u, v, f,
          viscous ? beta_ : 0.0};
      b.material.type().stress_pass(args, acc);
    }
#pragma omp barrier
    if (nth > 1) {
#pragma omp for schedule(static)
      for (std::size_t i = 0; i < ndof; ++i) {
        double sum = f_out[i];
        for (int t = 1; t < nth; ++t) sum += thread_forces_[static_cast<std::size_t>(t - 1)][i];
        f_out[i] = sum;
      }
    }
#pragma omp critical
    {
      total.energy += acc.energy;
      total.viscous_power += acc.viscous_power;
      if (acc.min_J < total.min_J) total.min_J = acc.min_J, total.min_J_element = acc.min_J_element;
      const double dt = viscous ? acc.dt : std::sqrt(acc.dt2);
      const double best = viscous ? total.dt : std::sqrt(total.dt2);
      if (dt < best) {
        total.dt = acc.dt, total.dt2 = acc.dt2;
        total.dt_element = acc.dt_element;
      }
    }
  }
  StressPassResult r;
  r.strain_energy = total.energy;
  r.viscous_power = total.viscous_power;
  r.critical_step = viscous ? total.dt : std::sqrt(total.dt2);
  r.limiting_element = total.dt_element;
  r.min_jacobian = total.min_J;
  r.min_jacobian_element = total.min_J_element;
  return r;
}

}  // namespace tactus::solver
