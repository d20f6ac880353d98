// The stress pass over all blocks, in parallel: the threads take the fixed partitions of every
// block as they come and call the block's law kernel (kernels/element_loop.hpp, compiled per law)
// once for each; the partitions' forces are then summed per node in partition order.
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

// Each of the lanes' tets adds a quarter of its current volume J V0 to its four nodes.
template <class T>
void add_quarter_volumes(const Model& m, std::size_t e, const double* u, double* node_volume, std::size_t node_offset) {
  const std::int32_t* c = &m.conn[4 * e];
  const T quarter =
      0.25 * kernel_detail::deformation_lanes<T>(m.grad.data(), m.conn.data(), u, e).J * kernel_detail::load_strided<T>(&m.volume[e], 1);
  for (int l = 0; l < lanes::lanes_of<T>; ++l)
    for (int k = 0; k < 4; ++k) node_volume[static_cast<std::size_t>(c[4 * l + k]) - node_offset] += lanes::lane(quarter, l);
}

// Each tet of [begin, end) adds V_e / 4 times the mean of `field` over its four nodes to each of
// them: a node's sum over its tets divided by its V_a is one averaging pass node -> tet -> node.
void add_quarter_means(const Model& m, std::size_t begin, std::size_t end, const double* field, double* node_sum, std::size_t node_offset) {
  for (std::size_t e = begin; e < end; ++e) {
    const std::int32_t* c = &m.conn[4 * e];
    const double share = 0.0625 * m.volume[e] * (field[c[0]] + field[c[1]] + field[c[2]] + field[c[3]]);
    for (int k = 0; k < 4; ++k) node_sum[static_cast<std::size_t>(c[k]) - node_offset] += share;
  }
}

// x[lo, hi) /= V (0 where the node has no tet of the block).
void divide_by_volume(const double* V, double* x, std::size_t lo, std::size_t hi) {
  for (std::size_t a = lo; a < hi; ++a) x[a] = V[a] > 0 ? x[a] / V[a] : 0.0;
}

}  // namespace

std::vector<double> anp_reference_node_volumes(const Model& m, const MaterialBlock& b) {
  std::vector<double> V(m.num_nodes, 0.0);
  for (std::size_t e = b.begin; e < b.end; ++e)
    for (int k = 0; k < 4; ++k) V[static_cast<std::size_t>(m.conn[4 * e + k])] += 0.25 * m.volume[e];
  return V;
}

void add_current_node_volumes(const Model& m, std::size_t begin, std::size_t end, const double* u, double* node_volume, std::size_t node_offset,
                              bool vectorised) {
  std::size_t e = begin;
  if (vectorised)
    for (; e + lanes::kLanes <= end; e += lanes::kLanes) add_quarter_volumes<lanes::Pack>(m, e, u, node_volume, node_offset);
  for (; e < end; ++e) add_quarter_volumes<double>(m, e, u, node_volume, node_offset);
}

// The serial form of InternalForces::anp_pass for one block (the reported stress, the tests).
std::vector<double> anp_nodal_pressure(const Model& m, const MaterialBlock& b, const double* u) {
  const std::vector<double> V = anp_reference_node_volumes(m, b);
  const std::size_t n = m.num_nodes;
  std::vector<double> x(n, 0.0), sum(n);
  add_current_node_volumes(m, b.begin, b.end, u, x.data());
  const int passes = b.material.pressure_smoothing();
  auto smooth = [&](bool last_of_volume) {
    std::fill(sum.begin(), sum.end(), 0.0);
    add_quarter_means(m, b.begin, b.end, x.data(), sum.data(), 0);
    x.swap(sum);
    if (!last_of_volume) divide_by_volume(V.data(), x.data(), 0, n);
  };
  if (passes > 0) divide_by_volume(V.data(), x.data(), 0, n);
  for (int i = 0; i < passes; ++i) smooth(i + 1 == passes);
  b.material.type().anp_nodal_pressure(b.material.law(), V.data(), x.data(), 0, n);
  for (int i = 0; i < passes; ++i) smooth(false);
  return x;
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
  block_pressure_.assign(model.blocks.size(), nullptr);
  for (std::size_t k = 0; k < model.blocks.size(); ++k)
    if (model.blocks[k].material.anp())
      anp_.push_back({k, anp_reference_node_volumes(model, model.blocks[k]), std::vector<double>(model.num_nodes, 0.0)});
  for (const AnpBlock& a : anp_) block_pressure_[a.block] = a.pressure.data();
  // Fixed partitions (independent of the thread count) and the node range each touches; the
  // Morton order of nodes and tets (model.cpp) keeps the ranges short.
  std::size_t forces = 0, volumes = 0;
  for (std::size_t k = 0; k < model.blocks.size(); ++k) {
    const MaterialBlock& b = model.blocks[k];
    if (b.material.rigid()) continue;  // moved as rigid bodies (time/rigid.cpp): no stress, no step limit
    const std::size_t n = b.end - b.begin,
                      parts = std::max<std::size_t>(1, std::min<std::size_t>(kPartitions, (n + kPartitionElements - 1) / kPartitionElements));
    for (std::size_t p = 0; p < parts; ++p) {
      Partition q{k, b.begin + n * p / parts, b.begin + n * (p + 1) / parts, model.num_nodes, 0, forces, volumes};
      for (std::size_t e = q.begin; e < q.end; ++e)
        for (int a = 0; a < 4; ++a) {
          const auto node = static_cast<std::size_t>(model.conn[4 * e + a]);
          q.node_lo = std::min(q.node_lo, node), q.node_hi = std::max(q.node_hi, node + 1);
        }
      if (q.begin == q.end) q.node_lo = q.node_hi = 0;
      forces += 3 * (q.node_hi - q.node_lo);
      if (b.material.anp()) volumes += q.node_hi - q.node_lo;
      partitions_.push_back(q);
    }
  }
  partition_forces_.assign(forces, 0.0);
  partition_volumes_.assign(volumes, 0.0);
  partition_acc_.resize(partitions_.size());
  chunk_partitions_.resize((model.num_nodes + kNodeChunk - 1) / kNodeChunk);
  for (std::size_t p = 0; p < partitions_.size(); ++p)
    for (std::size_t c = partitions_[p].node_lo / kNodeChunk; c * kNodeChunk < partitions_[p].node_hi; ++c) chunk_partitions_[c].push_back(p);
  chunk_anp_energy_.assign(chunk_partitions_.size(), 0.0);
}

int InternalForces::lanes() { return lanes::kLanes; }

void InternalForces::enable_mass_scaling() {
  mass_factor_.assign(model_.num_elements, 1.0);
  element_dt2_.assign(model_.num_elements, 0.0);
}

std::size_t InternalForces::memory_bytes() const {
  std::size_t b = (mass_factor_.capacity() + element_dt2_.capacity() + partition_forces_.capacity() + partition_volumes_.capacity()) * sizeof(double);
  b += partitions_.capacity() * sizeof(Partition) + partition_acc_.capacity() * sizeof(StressAccumulator);
  for (const auto& list : chunk_partitions_) b += list.capacity() * sizeof(std::size_t);
  for (const auto& a : anp_) b += (a.reference_volume.capacity() + a.pressure.capacity()) * sizeof(double);
  return b;
}

template <class Use>
void InternalForces::sum_chunk(std::size_t c, const std::vector<double>& arrays, std::size_t Partition::*offset, std::size_t width, double* out,
                               Use use) const {
  const std::size_t lo = c * kNodeChunk, hi = std::min(model_.num_nodes, lo + kNodeChunk);
  std::fill(out + width * lo, out + width * hi, 0.0);
  for (std::size_t p : chunk_partitions_[c]) {
    const Partition& q = partitions_[p];
    if (!use(q)) continue;
    const double* theirs = arrays.data() + q.*offset;
    for (std::size_t i = width * std::max(lo, q.node_lo); i < width * std::min(hi, q.node_hi); ++i) out[i] += theirs[i - width * q.node_lo];
  }
}

// The J pass of the ANP blocks, inside the parallel region (every thread calls it): the
// partitions' current tet volumes to their own nodal arrays, then per node chunk their sum in
// partition order, turned into pressures; chunk_anp_energy_ receives each chunk's part of the
// volumetric energy sum_a V_a U(J_a).
//
// With pressure smoothing (s passes of the averaging S: node -> tet -> node, V-weighted), the
// energy is sum_a V_a U((S^s J)_a): the nodal volume ratio is averaged s times before U' turns it
// into pressures, and since S is symmetric in the V-weighted inner product the forces it implies
// are those of the pressure averaged s times more (what the stress pass reads). S keeps a uniform
// field and damps a node-to-node oscillating one: the oscillation of the plain nodal pressure,
// which is not inf-sup stable and, when nearly incompressible, carries k times the tiny nodal
// volume ratio's oscillation, is averaged away while a smooth pressure keeps its constraint. The
// energy stays exactly conserved (a potential), and the volumetric stiffness only falls
// (||S x|| <= ||x||), so the element step estimate stays conservative.
void InternalForces::anp_pass(const double* u) {
#pragma omp single
  std::fill(chunk_anp_energy_.begin(), chunk_anp_energy_.end(), 0.0);
  for (AnpBlock& a : anp_) {
    const MaterialBlock& b = model_.blocks[a.block];
    const int passes = b.material.pressure_smoothing();
    const double* V = a.reference_volume.data();
    auto own = [&](const Partition& q) { return q.block == a.block; };
    // Per partition of the block: `add` its tets' shares to its own nodal array.
    auto scatter = [&](auto add) {
#pragma omp for schedule(dynamic, 1)
      for (std::size_t p = 0; p < partitions_.size(); ++p) {
        const Partition& q = partitions_[p];
        if (q.block != a.block) continue;
        double* mine = partition_volumes_.data() + q.volume_offset;
        std::fill(mine, mine + (q.node_hi - q.node_lo), 0.0);
        add(q, mine);
      }
    };
    // Per node chunk: the partitions' sums; then `finish` on the chunk's nodes [lo, hi).
    auto gather = [&](auto finish) {
#pragma omp for schedule(static)
      for (std::size_t c = 0; c < chunk_partitions_.size(); ++c) {
        sum_chunk(c, partition_volumes_, &Partition::volume_offset, 1, a.pressure.data(), own);
        finish(c, c * kNodeChunk, std::min(model_.num_nodes, (c + 1) * kNodeChunk));
      }
    };
    auto to_pressure = [&](std::size_t c, std::size_t lo, std::size_t hi) {
      chunk_anp_energy_[c] += b.material.type().anp_nodal_pressure(b.material.law(), V, a.pressure.data(), lo, hi);
    };
    auto to_mean = [&](std::size_t, std::size_t lo, std::size_t hi) { divide_by_volume(V, a.pressure.data(), lo, hi); };
    // One averaging pass of a.pressure (a nodal mean field) into the partitions' arrays.
    auto average = [&]() {
      scatter([&](const Partition& q, double* mine) { add_quarter_means(model_, q.begin, q.end, a.pressure.data(), mine, q.node_lo); });
    };
    scatter([&](const Partition& q, double* mine) { add_current_node_volumes(model_, q.begin, q.end, u, mine, q.node_lo, vectorised_); });
    if (passes == 0) {
      gather(to_pressure);
      continue;
    }
    gather(to_mean);  // the nodal volume ratio
    for (int i = 0; i < passes; ++i) {
      average();
      if (i + 1 < passes)
        gather(to_mean);
      else
        gather(to_pressure);  // the sums are V_a times the averaged ratio: nodal volumes, as U' takes them
    }
    for (int i = 0; i < passes; ++i) {
      average();
      gather(to_mean);
    }
  }
}

StressPassResult InternalForces::compute(const double* u, const double* v, double* f_out, StressSideTask side) {
  const bool viscous = beta_ > 0;
#pragma omp parallel num_threads(threads_)
  {
    if (!anp_.empty()) anp_pass(u);
    if (side.run) {
#pragma omp single nowait
      side.run(side.context);  // the partitions below are taken dynamically: this thread joins when done
    }
#pragma omp for schedule(dynamic, 1)
    for (std::size_t p = 0; p < partitions_.size(); ++p) {
      const Partition& q = partitions_[p];
      const MaterialBlock& b = model_.blocks[q.block];
      double* f = partition_forces_.data() + q.force_offset;
      std::fill(f, f + 3 * (q.node_hi - q.node_lo), 0.0);
      StressAccumulator acc;
      StressKernelArgs args{model_.conn.data(),
                            model_.grad.data(),
                            model_.volume.data(),
                            b.material.law(),
                            b.data(),
                            b.data_stride(),
                            b.begin,
                            q.begin,
                            q.end,
                            u,
                            v,
                            f,
                            q.node_lo,
                            viscous ? beta_ : 0.0};
      args.nodal_pressure = block_pressure_[q.block];
      args.vectorised = vectorised_;
      if (!mass_factor_.empty()) args.mass_factor = mass_factor_.data(), args.element_dt2 = element_dt2_.data();
      b.material.type().stress_pass(args, acc);
      partition_acc_[p] = acc;
    }
#pragma omp for schedule(static)
    for (std::size_t c = 0; c < chunk_partitions_.size(); ++c)
      sum_chunk(c, partition_forces_, &Partition::force_offset, 3, f_out, [](const Partition&) { return true; });
  }
  // The partitions' sums in partition order; ties of the smallest step or Jacobian go to the first.
  StressAccumulator total;
  for (const StressAccumulator& acc : partition_acc_) {
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
  for (double e : chunk_anp_energy_) total.energy += e;
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
