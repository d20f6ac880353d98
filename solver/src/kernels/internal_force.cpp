// One-point linear tets, total Lagrangian (paper eqs. 27-32): F = I + sum_a u_a (x) grad N_a,
// f_a = -V0 P grad N_a. Templated on the material so the inner loop has no virtual call or
// branch on the material; one switch per block.
#include "tactus/solver/internal_force.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

namespace tactus::solver {

namespace {

struct ThreadAccumulator {
  double energy = 0, viscous_power = 0;
  double dt2 = std::numeric_limits<double>::infinity();  // squared element step (no beta)
  double dt = std::numeric_limits<double>::infinity();   // element step with beta
  std::size_t dt_element = 0;
  double min_J = std::numeric_limits<double>::infinity();
  std::size_t min_J_element = 0;
};

template <class Mat, bool kViscous>
void element_range(const Model& m, const Mat& mat, std::size_t begin, std::size_t end, const double* __restrict u,
                   const double* __restrict v, double* __restrict f, double beta, const double* __restrict fibres,
                   ThreadAccumulator& acc) {
  const std::int32_t* __restrict conn = m.conn.data();
  const double* __restrict grad = m.grad.data();
  const double* __restrict vol = m.volume.data();
  const double rho0 = mat.density;
  const double visc_lambda = mat.small_strain_bulk() - 2.0 * mat.small_strain_shear() / 3.0;
  const double visc_mu = mat.small_strain_shear();
  for (std::size_t e = begin; e < end; ++e) {
    const std::int32_t* c = conn + 4 * e;
    const double* g = grad + 9 * e;
    Mat3 F = nodal_gradient(u, c, g);
    F(0, 0) += 1.0, F(1, 1) += 1.0, F(2, 2) += 1.0;
    const Mat3 cof = cofactor(F);
    const double J = F(0, 0) * cof(0, 0) + F(0, 1) * cof(0, 1) + F(0, 2) * cof(0, 2);
    if (J < acc.min_J) acc.min_J = J, acc.min_J_element = e;
    if (!(J > 0)) continue;  // reported by the caller; the step is abandoned
    StressPoint sp;
    if constexpr (std::is_same_v<Mat, Hgo>) {
      if (fibres)  // per-element directions (predictable branch: one value per block)
        sp = mat.evaluate(F, cof, J, Vec3d(fibres + 6 * e), Vec3d(fibres + 6 * e + 3));
      else
        sp = mat.evaluate(F, cof, J);
    } else {
      (void)fibres;
      sp = mat.evaluate(F, cof, J);
    }
    const double V0 = vol[e];
    acc.energy += V0 * sp.W;

    // Current shape-function gradients grad_x N_a = F^{-T} grad_X N_a = cof grad_X N_a / J;
    // s = sum_a |grad_x N_a|^2 is accumulated unscaled (J^2 s) to keep divisions out of the loop.
    double sJ2 = 0, sum[3] = {0, 0, 0};
    for (int a = 0; a < 3; ++a) {
      double h[3];
      for (int i = 0; i < 3; ++i) h[i] = cof(i, 0) * g[3 * a] + cof(i, 1) * g[3 * a + 1] + cof(i, 2) * g[3 * a + 2];
      sJ2 += h[0] * h[0] + h[1] * h[1] + h[2] * h[2];
      sum[0] += h[0], sum[1] += h[1], sum[2] += h[2];
    }
    sJ2 += sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2];
    // dt_e = L_e / c_e with L_e^2 = 1/s and c_e^2 = M J / rho0 (current density rho0 / J):
    // dt_e^2 = rho0 / (s M J) = rho0 J / (sJ2 M).
    const double dt2 = rho0 * J / (sJ2 * sp.modulus);

    if constexpr (kViscous) {
      // Rayleigh beta K v as a viscous stress: sigma_v = beta (lambda tr(D) I + 2 mu D),
      // D = sym(Fdot F^{-1}); its first Piola stress is J sigma_v F^{-T} = sigma_v cof.
      const Mat3 Fdot = nodal_gradient(v, c, g);
      const Mat3 L = Fdot * cof.transpose() / J;
      const Mat3 D = 0.5 * (L + L.transpose());
      const Mat3 sigma_v = beta * (visc_lambda * D.trace() * Mat3::Identity() + 2.0 * visc_mu * D);
      const Mat3 Pv = sigma_v * cof;
      sp.P += Pv;
      acc.viscous_power += V0 * (Pv.cwiseProduct(Fdot)).sum();
      const double omega = 2.0 / std::sqrt(dt2);
      const double xi = 0.5 * beta * omega;
      const double dt = 2.0 / omega * (std::sqrt(1.0 + xi * xi) - xi);
      if (dt < acc.dt) acc.dt = dt, acc.dt_element = e;
    } else {
      if (dt2 < acc.dt2) acc.dt2 = dt2, acc.dt_element = e;
    }

    double f0[3] = {0, 0, 0};
    for (int a = 0; a < 3; ++a) {
      double* fa = f + 3 * static_cast<std::size_t>(c[a + 1]);
      for (int i = 0; i < 3; ++i) {
        const double h = -V0 * (sp.P(i, 0) * g[3 * a] + sp.P(i, 1) * g[3 * a + 1] + sp.P(i, 2) * g[3 * a + 2]);
        fa[i] += h;
        f0[i] -= h;
      }
    }
    double* fz = f + 3 * static_cast<std::size_t>(c[0]);
    fz[0] += f0[0], fz[1] += f0[1], fz[2] += f0[2];
  }
}

template <bool kViscous>
void block_dispatch(const Model& m, const MaterialBlock& b, std::size_t begin, std::size_t end, const double* u,
                    const double* v, double* f, double beta, ThreadAccumulator& acc) {
  const double* fibres = b.element_fibres ? m.fibres.data() : nullptr;
  std::visit(
      [&](const auto& mat) { element_range<std::decay_t<decltype(mat)>, kViscous>(m, mat, begin, end, u, v, f, beta, fibres, acc); },
      b.material);
}

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
      if (viscous)
        block_dispatch<true>(model_, b, lo, hi, u, v, f, beta_, acc);
      else
        block_dispatch<false>(model_, b, lo, hi, u, v, f, beta_, acc);
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
