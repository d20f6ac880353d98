// The stress pass over all blocks, in parallel: each thread takes a contiguous share of every
// block and calls the block's law kernel (kernels/element_loop.hpp, compiled per law) once for it.
#include "tactus/solver/internal_force.hpp"

#include "element_loop.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <utility>

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

// Thread tid's contiguous share [lo, hi) of n items starting at begin.
std::pair<std::size_t, std::size_t> share(std::size_t begin, std::size_t n, int tid, int nth) {
  return {begin + n * static_cast<std::size_t>(tid) / static_cast<std::size_t>(nth),
          begin + n * static_cast<std::size_t>(tid + 1) / static_cast<std::size_t>(nth)};
}

double determinant_at(const Model& m, std::size_t e, const double* u) {
  Mat3 F = nodal_gradient(u, &m.conn[4 * e], &m.grad[9 * e]);
  F(0, 0) += 1.0, F(1, 1) += 1.0, F(2, 2) += 1.0;
  return F.determinant();
}

}  // namespace

std::vector<double> anp_reference_node_volumes(const Model& m, const MaterialBlock& b) {
  std::vector<double> V(m.num_nodes, 0.0);
  for (std::size_t e = b.begin; e < b.end; ++e)
    for (int k = 0; k < 4; ++k) V[static_cast<std::size_t>(m.conn[4 * e + k])] += 0.25 * m.volume[e];
  return V;
}

void add_current_node_volumes(const Model& m, std::size_t begin, std::size_t end, const double* u, double* node_volume) {
  for (std::size_t e = begin; e < end; ++e) {
    const double quarter = 0.25 * determinant_at(m, e, u) * m.volume[e];
    const std::int32_t* c = &m.conn[4 * e];
    node_volume[c[0]] += quarter, node_volume[c[1]] += quarter, node_volume[c[2]] += quarter, node_volume[c[3]] += quarter;
  }
}

std::vector<double> anp_nodal_pressure(const Model& m, const MaterialBlock& b, const double* u) {
  const std::vector<double> V = anp_reference_node_volumes(m, b);
  std::vector<double> p(m.num_nodes, 0.0);
  add_current_node_volumes(m, b.begin, b.end, u, p.data());
  b.material.type().anp_nodal_pressure(b.material.law(), V.data(), p.data(), 0, m.num_nodes);
  return p;
}

std::vector<Mat3> element_cauchy_stress(const Model& m, const double* u) {
  std::vector<Mat3> sigma(m.num_elements);
  for (const MaterialBlock& b : m.blocks) {
    const std::vector<double> p = b.material.anp() ? anp_nodal_pressure(m, b, u) : std::vector<double>();
    for (std::size_t e = b.begin; e < b.end; ++e) {
      const std::int32_t* c = &m.conn[4 * e];
      const Mat3 F = Mat3::Identity() + nodal_gradient(u, c, &m.grad[9 * e]);
      const Mat3 P = b.material.anp() ? b.material.evaluate_with_pressure(F, 0.25 * (p[c[0]] + p[c[1]] + p[c[2]] + p[c[3]]), b.data_of(e)).P
                                      : b.material.evaluate(F, b.data_of(e)).P;
      sigma[e] = cauchy_stress(F, P);
    }
  }
  return sigma;
}

InternalForces::InternalForces(const Model& model, double beta, int threads)
    : model_(model), beta_(beta), threads_(threads > 0 ? threads : default_threads(model.num_elements)) {
  thread_forces_.resize(static_cast<std::size_t>(threads_ - 1));
  for (auto& buf : thread_forces_) buf.assign(3 * model.num_nodes, 0.0);
  block_pressure_.assign(model.blocks.size(), nullptr);
  for (std::size_t k = 0; k < model.blocks.size(); ++k)
    if (model.blocks[k].material.anp())
      anp_.push_back({k, anp_reference_node_volumes(model, model.blocks[k]), std::vector<double>(model.num_nodes, 0.0)});
  for (const AnpBlock& a : anp_) block_pressure_[a.block] = a.pressure.data();
  if (!anp_.empty()) thread_node_volumes_.assign(static_cast<std::size_t>(threads_ - 1), std::vector<double>(model.num_nodes, 0.0));
}

void InternalForces::enable_mass_scaling() {
  mass_factor_.assign(model_.num_elements, 1.0);
  element_dt2_.assign(model_.num_elements, 0.0);
}

std::size_t InternalForces::memory_bytes() const {
  std::size_t b = (mass_factor_.capacity() + element_dt2_.capacity()) * sizeof(double);
  for (const auto& buf : thread_forces_) b += buf.capacity() * sizeof(double);
  for (const auto& buf : thread_node_volumes_) b += buf.capacity() * sizeof(double);
  for (const auto& a : anp_) b += (a.reference_volume.capacity() + a.pressure.capacity()) * sizeof(double);
  return b;
}

// The J pass of the ANP blocks, inside the parallel region (every thread calls it): each thread
// adds its share of the block's current tet volumes to its own nodal array, then sums a share of
// the nodes over the threads and turns them into pressures. Returns this thread's part of the
// volumetric energy sum_a V_a U(J_a).
double InternalForces::anp_pass(const double* u, int tid, int nth) {
  double energy = 0;
  const std::size_t N = model_.num_nodes;
  for (AnpBlock& a : anp_) {
    const MaterialBlock& b = model_.blocks[a.block];
    double* mine = tid == 0 ? a.pressure.data() : thread_node_volumes_[static_cast<std::size_t>(tid - 1)].data();
    std::fill(mine, mine + N, 0.0);
    const auto [lo, hi] = share(b.begin, b.end - b.begin, tid, nth);
    add_current_node_volumes(model_, lo, hi, u, mine);
#pragma omp barrier
    const auto [nlo, nhi] = share(0, N, tid, nth);
    for (int t = 1; t < nth; ++t) {
      const double* other = thread_node_volumes_[static_cast<std::size_t>(t - 1)].data();
      for (std::size_t i = nlo; i < nhi; ++i) a.pressure[i] += other[i];
    }
    energy += b.material.type().anp_nodal_pressure(b.material.law(), a.reference_volume.data(), a.pressure.data(), nlo, nhi);
#pragma omp barrier
  }
  return energy;
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
    if (!anp_.empty()) acc.energy += anp_pass(u, tid, nth);
    for (std::size_t k = 0; k < model_.blocks.size(); ++k) {
      const MaterialBlock& b = model_.blocks[k];
      // Static contiguous split: each thread touches a compact set of nodes.
      const auto [lo, hi] = share(b.begin, b.end - b.begin, tid, nth);
      StressKernelArgs args{
          model_.conn.data(),   model_.grad.data(), model_.volume.data(), b.material.law(), b.data(), b.data_stride(), b.begin, lo, hi, u, v, f,
          viscous ? beta_ : 0.0};
      args.nodal_pressure = block_pressure_[k];
      if (!mass_factor_.empty()) args.mass_factor = mass_factor_.data(), args.element_dt2 = element_dt2_.data();
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
