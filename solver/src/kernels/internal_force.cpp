// The stress pass over all blocks, in parallel: the threads take the fixed partitions of every
// block as they come and call the block's law kernel (kernels/element_loop.hpp, compiled per law)
// once for each; the partitions' forces are then summed per node in partition order.
#include "tactus/solver/internal_force.hpp"

#include "tactus/core/error.hpp"

#include "element_loop.hpp"
#include "tactus/solver/rigid.hpp"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <iterator>
#include <limits>
#include <numeric>
#include <stdexcept>
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

// x[lo, hi) /= V (0 where the node has no tet of the block).
void divide_by_volume(const double* V, double* x, std::size_t lo, std::size_t hi) {
  for (std::size_t a = lo; a < hi; ++a) x[a] = V[a] > 0 ? x[a] / V[a] : 0.0;
}

// x[lo, hi) *= V: a nodal mean volume ratio back to the nodal volumes U' takes.
void times_volume(const double* V, double* x, std::size_t lo, std::size_t hi) {
  for (std::size_t a = lo; a < hi; ++a) x[a] *= V[a];
}

// The ANP tiles of a partition's tets (InternalForces::anp_tiles_).
std::size_t tiles_of(std::size_t tets) { return (tets + kAnpTile - 1) / kAnpTile; }
static_assert(kForceStride == InternalForces::kSlotDoubles);
// Whole tiles per atom: every tile is then the same 16 tets of its block at any rank count.
static_assert(kAtomTets % kAnpTile == 0);

}  // namespace

NodeAveraging::NodeAveraging(const Model& m, const MaterialBlock& b, const std::vector<double>& V) {
  const std::size_t n = m.num_nodes;
  const auto [first, tets] = block_node_tets(m, b);
  row.assign(n + 1, 0);
  std::vector<double> sum(n, 0.0);  // a's row, summed over its tets in element order
  std::vector<std::int32_t> neighbours;
  for (std::size_t a = 0; a < n; ++a) {
    neighbours.clear();
    for (std::size_t t = first[a]; t < first[a + 1]; ++t)
      for (int k = 0; k < 4; ++k) {
        const std::int32_t node = m.conn[4 * tets[t] + k];
        if (static_cast<std::size_t>(node) == a) continue;
        if (sum[static_cast<std::size_t>(node)] == 0.0) neighbours.push_back(node);
        sum[static_cast<std::size_t>(node)] += m.volume[tets[t]] / 16.0;
      }
    std::sort(neighbours.begin(), neighbours.end());
    for (const std::int32_t node : neighbours) {
      column.push_back(node);
      weight.push_back(sum[static_cast<std::size_t>(node)] / V[a]);
      sum[static_cast<std::size_t>(node)] = 0.0;
    }
    row[a + 1] = column.size();
  }
  column.shrink_to_fit();
  weight.shrink_to_fit();
}

std::vector<double> anp_reference_node_volumes(const Model& m, const MaterialBlock& b) {
  std::vector<double> V(m.num_nodes, 0.0);
  for (std::size_t e = b.begin; e < b.end; ++e)
    for (int k = 0; k < 4; ++k) V[static_cast<std::size_t>(m.conn[4 * e + k])] += 0.25 * m.volume[e];
  return V;
}

// Each tet of [begin, end) adds a quarter of its current volume v = J V0 to its four nodes, v from
// its current edges from node 0, (X_k - X_0) + (u_k - u_0) (the reference and the displacement
// differenced apart, so nothing cancels against the absolute coordinates): v = e1 . (e2 x e3) / 6,
// positive for a tet that keeps its orientation (inverted input tets are refused in model.cpp).
// Not through F = I + grad u and not in SIMD lanes: the pass is gathers and scatters around a few
// flops, and the nine reference gradients are 72 bytes per tet more to stream (bench: one thread,
// 10k tets, J pass ~6.2 ns per tet in lanes through F, ~4.5 ns like this).
void add_current_node_volumes(const Model& m, const std::int32_t* conn, std::size_t count, const double* u, double* node_volume,
                              const std::uint16_t* slot) {
  const double* X = m.X.data();
  for (std::size_t e = 0; e < count; ++e) {
    const std::int32_t* c = conn + 4 * e;
    if (e + kPrefetchAhead < count)  // the gathers' misses dominate on large meshes, as in the stress pass
      for (int k = 0; k < 4; ++k) {
        const auto node = static_cast<std::size_t>(c[4 * kPrefetchAhead + k]);
        __builtin_prefetch(X + 3 * node);
        __builtin_prefetch(u + 3 * node);
        __builtin_prefetch(node_volume + (slot ? std::size_t{slot[4 * (e + kPrefetchAhead) + static_cast<std::size_t>(k)]} : node), 1);
      }
    const std::size_t n0 = 3 * static_cast<std::size_t>(c[0]);
    double edge[3][3];  // edge[k]: from node 0 to node k + 1
    for (int k = 0; k < 3; ++k) {
      const std::size_t n = 3 * static_cast<std::size_t>(c[k + 1]);
      for (int i = 0; i < 3; ++i) edge[k][i] = (X[n + i] - X[n0 + i]) + (u[n + i] - u[n0 + i]);
    }
    const double quarter = (1.0 / 24.0) * (edge[0][0] * (edge[1][1] * edge[2][2] - edge[1][2] * edge[2][1]) +
                                           edge[0][1] * (edge[1][2] * edge[2][0] - edge[1][0] * edge[2][2]) +
                                           edge[0][2] * (edge[1][0] * edge[2][1] - edge[1][1] * edge[2][0]));
    for (int k = 0; k < 4; ++k)
      node_volume[slot ? std::size_t{slot[4 * e + static_cast<std::size_t>(k)]} : static_cast<std::size_t>(c[k])] += quarter;
  }
}

namespace {

// The node stages of pressure smoothing (s passes of S, s >= 0), shared by the parallel J pass and
// the serial form below. x holds the nodal volume ratio J_a, y is scratch; `for_nodes(f)` calls
// f(lo, hi) over the nodes whose values this process computes and returns once they are done (a
// barrier in the parallel pass), `share(x)` then brings the values other processes computed (on
// ranks; else nothing), and `to_pressure(x)` turns volume ratios into pressures U' (and the
// energy sum_a V_a U). The ratio is averaged s times, turned into pressures, and the pressures
// averaged s more times; they end in x (2s buffer swaps).
template <class ForNodes, class Share, class ToPressure>
void smooth_to_pressure(const NodeAveraging& S, int passes, double*& x, double*& y, ForNodes for_nodes, Share share, ToPressure to_pressure) {
  for (int i = 0; i < passes; ++i) {
    for_nodes([&](std::size_t lo, std::size_t hi) { S.apply(x, y, lo, hi); });
    std::swap(x, y);
    share(x);
  }
  to_pressure(x);
  for (int i = 0; i < passes; ++i) {
    for_nodes([&](std::size_t lo, std::size_t hi) { S.apply(x, y, lo, hi); });
    std::swap(x, y);
    if (i + 1 < passes) share(x);  // the stress pass reads only the nodes this process computes
  }
}

}  // namespace

// The serial form of InternalForces::anp_pass for one block (the reported stress, the tests).
std::vector<double> anp_nodal_pressure(const Model& m, const MaterialBlock& b, const double* u) {
  const std::vector<double> V = anp_reference_node_volumes(m, b);
  const std::size_t n = m.num_nodes;
  std::vector<double> x(n, 0.0);
  add_current_node_volumes(m, &m.conn[4 * b.begin], b.end - b.begin, u, x.data());
  if (b.material.pressure_smoothing() == 0) {
    b.material.type().anp_nodal_pressure(b.material.law(), V.data(), x.data(), 0, n);
    return x;
  }
  divide_by_volume(V.data(), x.data(), 0, n);
  std::vector<double> y(n);
  double *in = x.data(), *out = y.data();
  smooth_to_pressure(
      NodeAveraging(m, b, V), b.material.pressure_smoothing(), in, out, [&](auto f) { f(0, n); }, [](double*) {},
      [&](double* ratio) {
        times_volume(V.data(), ratio, 0, n);
        b.material.type().anp_nodal_pressure(b.material.law(), V.data(), ratio, 0, n);
      });
  return in == x.data() ? x : y;
}

namespace {

// The reported Cauchy stress of one tet of block b (nodes c, deformation gradient F, law data d):
// 0 in a joint gap (placed by the bones, no stress: model.hpp); with nodal pressures p (an ANP
// block) its volumetric part is the mean of its nodes', with no volume floor where rigid pieces
// place all four nodes (as in the stress pass); p null: the law's own stress.
Mat3 reported_cauchy_stress(const MaterialBlock& b, const Mat3& F, const std::int32_t* c, const double* p, const char* rigid, const double* d) {
  if (b.joint_gap) return Mat3::Zero();
  if (!p) return cauchy_stress(F, b.material.evaluate(F, d).P);
  const bool placed = rigid[c[0]] && rigid[c[1]] && rigid[c[2]] && rigid[c[3]];
  return cauchy_stress(F, b.material.evaluate_with_pressure(F, 0.25 * (p[c[0]] + p[c[1]] + p[c[2]] + p[c[3]]), d, !placed).P);
}

}  // namespace

std::vector<Mat3> element_cauchy_stress(const Model& m, const double* u) {
  std::vector<Mat3> sigma(m.num_elements, Mat3::Zero());
  const bool any_anp = std::any_of(m.blocks.begin(), m.blocks.end(), [](const MaterialBlock& b) { return b.material.anp(); });
  const std::vector<char> rigid = any_anp ? rigid_nodes(m) : std::vector<char>();
  for (const MaterialBlock& b : m.blocks) {
    const std::vector<double> p = !b.joint_gap && b.material.anp() ? anp_nodal_pressure(m, b, u) : std::vector<double>();
    for (std::size_t e = b.begin; e < b.end; ++e) {
      const std::int32_t* c = &m.conn[4 * e];
      const Mat3 F = Mat3::Identity() + nodal_gradient(u, c, &m.grad[9 * e]);
      sigma[e] = reported_cauchy_stress(b, F, c, p.empty() ? nullptr : p.data(), rigid.data(), b.data_of(e));
    }
  }
  return sigma;
}

InternalForces::InternalForces(const Model& model, double beta, int threads)
    : model_(model), beta_(beta), threads_(threads > 0 ? threads : default_threads(model.num_elements)) {
  if (model.tet_geometry_released) throw std::logic_error("InternalForces: the model's tet geometry was released (Model::release_tet_geometry)");
  block_pressure_.assign(model.blocks.size(), nullptr);
  for (std::size_t k = 0; k < model.blocks.size(); ++k)
    if (model.blocks[k].material.anp() && model.blocks[k].has_stress_pass()) {
      AnpBlock a{k, anp_reference_node_volumes(model, model.blocks[k]), std::vector<double>(model.num_nodes, 0.0), {}, {}, {}};
      a.bound_factor = anp_step_bound_factors(model, model.blocks[k], a.reference_volume);
      if (model.blocks[k].material.pressure_smoothing() > 0) {
        a.averaging = NodeAveraging(model, model.blocks[k], a.reference_volume);
        a.smoothed.assign(model.num_nodes, 0.0);
      }
      const std::vector<double> rest =
          anp_rest_rows(model, model.blocks[k], a.reference_volume, model.blocks[k].material.pressure_smoothing() > 0 ? &a.averaging : nullptr);
      // (A rigid block has no stress pass, so no volumetric rows to take out of its nodes' rows.)
      const std::vector<double> reference =
          model.blocks[k].material.rigid() ? std::vector<double>(model.num_nodes, 0.0) : anp_reference_rows(model, model.blocks[k], a.bound_factor);
      anp_rest_rows_.resize(model.num_nodes, 0.0);
      anp_reference_rows_.resize(model.num_nodes, 0.0);
      for (std::size_t n = 0; n < model.num_nodes; ++n) anp_rest_rows_[n] += rest[n], anp_reference_rows_[n] += reference[n];
      anp_.push_back(std::move(a));
    }
  for (const AnpBlock& a : anp_) block_pressure_[a.block] = a.pressure.data();
  if (!anp_.empty()) rigid_node_ = rigid_nodes(model);
  const std::size_t tiles = build_atoms();
  // Per node, the tiles holding its ANP tets (ascending: partitions and their tets in order).
  anp_node_tile_first_.assign(model.num_nodes + 1, 0);
  for (int fill = 0; fill < 2; ++fill) {
    std::vector<std::size_t> last(model.num_nodes, tiles), next(anp_node_tile_first_.begin(), anp_node_tile_first_.end() - 1);
    if (fill) anp_node_tiles_.resize(anp_node_tile_first_.back());
    for (const Partition& q : partitions_)
      if (model.blocks[q.block].material.anp())
        for (std::size_t e = q.begin; e < q.end; ++e)
          for (int a = 0; a < 4; ++a) {
            const auto node = static_cast<std::size_t>(model.conn[4 * e + a]);
            const std::size_t tile = q.tile_offset + (e - q.begin) / kAnpTile;
            if (last[node] == tile) continue;
            last[node] = tile;
            if (fill)
              anp_node_tiles_[next[node]++] = static_cast<std::uint32_t>(tile);
            else
              ++anp_node_tile_first_[node + 1];
          }
    if (!fill)
      for (std::size_t a = 0; a < model.num_nodes; ++a) anp_node_tile_first_[a + 1] += anp_node_tile_first_[a];
  }
  partition_acc_.resize(partitions_.size());
  num_chunks_ = (model.num_nodes + kNodeChunk - 1) / kNodeChunk;
  // One process runs every atom and chunk (own_atoms narrows these to a rank's).
  sum_chunks_.resize(num_chunks_), anp_volume_atoms_.resize(partitions_.size());
  std::iota(sum_chunks_.begin(), sum_chunks_.end(), std::size_t{0});
  std::iota(anp_volume_atoms_.begin(), anp_volume_atoms_.end(), std::size_t{0});
  chunk_anp_energy_.assign(num_chunks_, 0.0);
  chunk_rank_.assign(num_chunks_, 0);
  const std::vector<char> every(model.num_nodes, 1);
  set_anp_runs(every, every, 0);
  set_nodal_step_bound(model.mass.data());
}

// The partitions are the atoms (independent of the thread and rank count): each gets one slot per
// node its tets touch, ascending, and each corner of its tets the slot of its node; each node the
// list of its slots, which atom order makes ascending. Returns the number of ANP tiles.
std::size_t InternalForces::build_atoms() {
  const Model& model = model_;
  std::size_t slots = 0, tiles = 0;
  tet_slot_.assign(4 * model.num_elements, 0);
  block_slot_begin_.assign(model.blocks.size(), 0), block_slot_end_.assign(model.blocks.size(), 0);
  std::vector<std::uint32_t> nodes, slot_node;  // slot_node: each slot's node (the atoms' sorted node lists, in atom order)
  for (std::size_t k = 0; k < model.blocks.size(); ++k) {
    const MaterialBlock& b = model.blocks[k];
    block_slot_begin_[k] = slots;
    if (b.has_stress_pass())  // else moved as rigid bodies (time/rigid.cpp) or placed by them: no stress, no step limit
      for (std::size_t start = b.begin; start < std::max(b.end, b.begin + 1); start += kAtomTets) {
        Partition q{k, start, std::min(b.end, start + kAtomTets), slots, slots, tiles, 4 * start};
        nodes.assign(model.conn.begin() + static_cast<std::ptrdiff_t>(4 * q.begin), model.conn.begin() + static_cast<std::ptrdiff_t>(4 * q.end));
        std::sort(nodes.begin(), nodes.end());
        nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
        for (std::size_t corner = 4 * q.begin; corner < 4 * q.end; ++corner)
          tet_slot_[corner] = static_cast<std::uint16_t>(
              std::lower_bound(nodes.begin(), nodes.end(), static_cast<std::uint32_t>(model.conn[corner])) - nodes.begin());
        q.slot_end = slots += nodes.size();
        slot_node.insert(slot_node.end(), nodes.begin(), nodes.end());
        if (b.material.anp()) tiles += tiles_of(q.end - q.begin);
        partitions_.push_back(q);
      }
    block_slot_end_[k] = slots;
  }
  static_assert(4 * kAtomTets <= 65536, "an atom's slots must fit tet_slot_'s 16 bits");
  for (std::size_t p = 0; p < partitions_.size(); ++p) interior_atoms_.push_back(p);
  partition_forces_.assign(kForceStride * slots, 0.0);
  partition_volumes_.assign(slots, 0.0);
  anp_tiles_.assign(tiles, 0.0);
  // Each node's slots, in atom order (a counting pass, then a filling one).
  node_slot_first_.assign(model.num_nodes + 1, 0);
  node_slots_.resize(slots);
  for (std::uint32_t n : slot_node) ++node_slot_first_[n + 1];
  for (std::size_t a = 0; a < model.num_nodes; ++a) node_slot_first_[a + 1] += node_slot_first_[a];
  std::vector<std::size_t> next(node_slot_first_.begin(), node_slot_first_.end() - 1);
  for (std::size_t s = 0; s < slots; ++s) node_slots_[next[slot_node[s]]++] = static_cast<std::uint32_t>(s);
  return tiles;
}

int InternalForces::lanes() { return lanes::kLanes; }

void InternalForces::enable_mass_scaling() {
  const std::size_t tets = holds_geometry_ ? held_volume_.size() : model_.num_elements;
  mass_factor_.assign(tets, 1.0);
  element_dt2_.assign(tets, 0.0);
}

std::size_t InternalForces::memory_bytes() const {
  std::size_t b = (mass_factor_.capacity() + element_dt2_.capacity() + partition_forces_.capacity() + partition_volumes_.capacity() +
                   nodal_bound_.capacity() + chunk_bound_.capacity()) *
                  sizeof(double);
  b += (anp_tiles_.capacity() + anp_reference_rows_.capacity() + anp_rest_rows_.capacity() + chunk_eta_bound_.capacity()) * sizeof(double);
  b += anp_node_tile_first_.capacity() * sizeof(std::size_t) + anp_node_tiles_.capacity() * sizeof(std::uint32_t);
  b += node_moves_.capacity() + rigid_node_.capacity() + touched_.capacity() +
       (chunk_bound_node_.capacity() + chunk_eta_node_.capacity()) * sizeof(std::size_t);
  b += partitions_.capacity() * sizeof(Partition) + partition_acc_.capacity() * sizeof(StressAccumulator);
  b += held_conn_.capacity() * sizeof(std::int32_t) + (held_grad_.capacity() + held_volume_.capacity() + held_data_.capacity()) * sizeof(double);
  b += tet_slot_.capacity() * sizeof(std::uint16_t) + node_slot_first_.capacity() * sizeof(std::size_t) +
       node_slots_.capacity() * sizeof(std::uint32_t);
  b += (block_slot_begin_.capacity() + block_slot_end_.capacity() + boundary_atoms_.capacity() + interior_atoms_.capacity()) * sizeof(std::size_t);
  b += (sum_chunks_.capacity() + anp_volume_atoms_.capacity()) * sizeof(std::size_t) +
       (anp_runs_.capacity() + anp_convert_runs_.capacity()) * sizeof(NodeRun) + convert_energy_.capacity() * sizeof(double);
  for (const NodeGhosts& g : anp_ghosts_) b += (g.send.capacity() + g.receive.capacity()) * sizeof(std::uint32_t);
  b += partition_rank_.capacity() * sizeof(int) + node_rank_.capacity() * sizeof(std::int32_t) + halo_.capacity() * sizeof(HaloSlots);
  for (const HaloSlots& h : halo_)
    b += (h.send.capacity() + h.receive.capacity() + h.send_tiles.capacity() + h.receive_tiles.capacity()) * sizeof(std::uint32_t);
  for (const auto& a : anp_)
    b += (a.reference_volume.capacity() + a.pressure.capacity() + a.bound_factor.capacity() + a.smoothed.capacity()) * sizeof(double) +
         a.averaging.memory_bytes();
  return b;
}

template <std::size_t kStride, std::size_t kWidth>
void InternalForces::sum_nodes(std::size_t lo, std::size_t hi, const std::vector<double>& arrays, std::size_t slot_lo, std::size_t slot_hi,
                               double* out, double* extra, const char* only) const {
  static_assert(kWidth <= kStride);
  for (std::size_t n = lo; n < hi; ++n) {
    double sum[kWidth] = {}, more = 0;
    if (only && !only[n]) {  // no slot of this process holds a value here: the sum is 0
      for (std::size_t i = 0; i < kWidth; ++i) out[kWidth * n + i] = 0;
      if (extra) extra[n] = 0;
      continue;
    }
    for (std::size_t k = node_slot_first_[n]; k < node_slot_first_[n + 1]; ++k) {
      const std::size_t s = node_slots_[k];
      if (s < slot_lo || s >= slot_hi) continue;
      const double* t = arrays.data() + kStride * s;
      for (std::size_t i = 0; i < kWidth; ++i) sum[i] += t[i];
      if constexpr (kWidth < kStride) more += t[kWidth];
    }
    for (std::size_t i = 0; i < kWidth; ++i) out[kWidth * n + i] = sum[i];
    if (extra) extra[n] = more;
  }
}

// The J pass of the ANP blocks, inside the parallel region (every thread calls it): the
// partitions' current tet volumes to their own nodal arrays, then per node their sum in partition
// order, turned into pressures; chunk_anp_energy_ receives each chunk's part of the volumetric
// energy sum_a V_a U(J_a).
//
// With pressure smoothing (s passes of the averaging S: node -> tet -> node, V-weighted), the
// energy is sum_a V_a U((S^s J)_a): the nodal volume ratio is averaged s times before U' turns it
// into pressures, and since S is symmetric in the V-weighted inner product the forces it implies
// are those of the pressure averaged s times more (what the stress pass reads). S keeps a uniform
// field and damps a node-to-node oscillating one: the oscillation of the plain nodal pressure,
// which is not inf-sup stable and, when nearly incompressible, carries k times the tiny nodal
// volume ratio's oscillation, is averaged away while a smooth pressure keeps its constraint. The
// energy stays exactly conserved (a potential), and the volumetric stiffness only falls
// (||S x|| <= ||x||), so the element step estimate stays conservative. S is applied as the
// node-to-node operator NodeAveraging (built once): each pass is one read of the node rows, where
// applying it tet by tet (a scatter into the partitions' arrays, then their sums per chunk) cost
// two loops and two barriers per pass.
//
// On ranks each node pass runs over the rank's own nodes, and the master thread then brings its
// ghost nodes' values from their owners (exchange.nodes, between barriers); the ANP atoms' volumes
// at shared nodes travel once, before the sums (exchange.volumes). Every value a rank uses is then
// the one-process value (anp_ghosts_of_rank).
void InternalForces::anp_pass(const double* u, const StressExchange& exchange) {
  const auto share = [&](double* values) {
    if (!exchange.nodes) return;
#pragma omp master
    exchange.nodes(exchange.context, values);
#pragma omp barrier
  };
  const auto for_nodes = [&](auto f) {
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < anp_runs_.size(); ++i) f(anp_runs_[i].lo, anp_runs_[i].hi);
  };
#pragma omp single
  std::fill(chunk_anp_energy_.begin(), chunk_anp_energy_.end(), 0.0);
  for (AnpBlock& a : anp_) {
    const MaterialBlock& b = model_.blocks[a.block];
    const double* V = a.reference_volume.data();
    // Per partition of the block: its tets' current volumes to its own nodal array.
#pragma omp for schedule(dynamic, 1)
    for (std::size_t i = 0; i < anp_volume_atoms_.size(); ++i) {
      const std::size_t p = anp_volume_atoms_[i];
      const Partition& q = partitions_[p];
      if (q.block != a.block) continue;
      double* mine = partition_volumes_.data() + q.slot_begin;
      std::fill(mine, mine + (q.slot_end - q.slot_begin), 0.0);
      add_current_node_volumes(model_, tet_conn() + 4 * held_index(q.held_tet, q.begin), q.end - q.begin, u, mine, tet_slot_.data() + q.corner_begin);
    }
    if (exchange.volumes) {
#pragma omp master
      exchange.volumes(exchange.context);
#pragma omp barrier
    }
    // Per node: the partitions' sums (the current nodal volume), and with smoothing the ratio to V.
    const bool smoothing = b.material.pressure_smoothing() > 0;
    for_nodes([&](std::size_t lo, std::size_t hi) {
      sum_nodes<1, 1>(lo, hi, partition_volumes_, block_slot_begin_[a.block], block_slot_end_[a.block], a.pressure.data());
      if (smoothing) divide_by_volume(V, a.pressure.data(), lo, hi);
    });
    share(a.pressure.data());
    double *x = a.pressure.data(), *y = a.smoothed.data();
    smooth_to_pressure(a.averaging, b.material.pressure_smoothing(), x, y, for_nodes, share, [&](double* ratio) {
#pragma omp for schedule(static)
      for (std::size_t i = 0; i < anp_convert_runs_.size(); ++i) {
        const NodeRun& r = anp_convert_runs_[i];
        if (smoothing) times_volume(V, ratio, r.lo, r.hi);
        convert_energy_[i] = b.material.type().anp_nodal_pressure(b.material.law(), V, ratio, r.lo, r.hi);
      }
#pragma omp single
      for (std::size_t i = 0; i < anp_convert_runs_.size(); ++i)
        if (anp_convert_runs_[i].reported) chunk_anp_energy_[anp_convert_runs_[i].chunk] += convert_energy_[i];
    });
  }
}

// One atom's stress pass into its slots and partition_acc_[p].
void InternalForces::stress_partition(std::size_t p, const double* u, const double* v, bool viscous) {
  const Partition& q = partitions_[p];
  const MaterialBlock& b = model_.blocks[q.block];
  double* f = partition_forces_.data() + kForceStride * q.slot_begin;
  std::fill(f, f + kForceStride * (q.slot_end - q.slot_begin), 0.0);
  StressAccumulator acc;
  const std::size_t at = held_index(q.held_tet, q.begin);
  const double* data = !b.per_element_data() ? b.data() : holds_geometry_ ? held_data_.data() + q.held_data : b.data_of(q.begin);
  StressKernelArgs args{tet_conn() + 4 * at,
                        tet_grad() + 9 * at,
                        tet_volume() + at,
                        b.material.law(),
                        data,
                        b.data_stride(),
                        b.begin,
                        q.begin,
                        q.end,
                        u,
                        v,
                        f,
                        tet_slot_.data() + q.corner_begin,
                        viscous ? beta_ : 0.0};
  args.nodal_pressure = block_pressure_[q.block];
  if (args.nodal_pressure) {
    args.anp_volume_floor = b.material.volume_floor(), args.anp_floor_stiffness = b.material.small_strain_bulk();
    args.rigid_node = rigid_node_.data();
  }
  if (nodal_mass_) {
    args.nodal_bound = true;
    for (const AnpBlock& an : anp_)
      if (an.block == q.block) {
        args.anp_bound_factor = an.bound_factor.data(), args.anp_bulk = b.material.small_strain_bulk();
        args.anp_tiles = anp_tiles_.data() + q.tile_offset;
        std::fill(args.anp_tiles, args.anp_tiles + tiles_of(q.end - q.begin), 0.0);
      }
  }
  args.vectorised = vectorised_;
  if (!mass_factor_.empty()) args.mass_factor = mass_factor_.data() + at, args.element_dt2 = element_dt2_.data() + at;
  b.material.type().stress_pass(args, acc);
  partition_acc_[p] = acc;
}

StressPassResult InternalForces::compute(const double* u, const double* v, double* f_out, StressSideTask side, StressExchange exchange) {
  const bool viscous = beta_ > 0;
#pragma omp parallel num_threads(threads_)
  {
    if (!anp_.empty()) anp_pass(u, exchange);
    if (side.run) {
#pragma omp single nowait
      side.run(side.context);  // the partitions below are taken dynamically: this thread joins when done
    }
    // On ranks: the atoms whose slots other ranks need first, then their exchange starts (the
    // master thread: MPI_THREAD_FUNNELED) while the others' interior atoms run, and it ends before
    // the sums. One process: every atom is interior.
#pragma omp for schedule(dynamic, 1)
    for (std::size_t i = 0; i < boundary_atoms_.size(); ++i) stress_partition(boundary_atoms_[i], u, v, viscous);
    if (exchange.start) {
#pragma omp master
      exchange.start(exchange.context);
    }
#pragma omp for schedule(dynamic, 1)
    for (std::size_t i = 0; i < interior_atoms_.size(); ++i) stress_partition(interior_atoms_[i], u, v, viscous);
    if (exchange.finish) {
#pragma omp master
      exchange.finish(exchange.context);
#pragma omp barrier
    }
    // On ranks only the chunks holding a node this rank's atoms touch: the others' forces come from
    // their owners (ranks.hpp), and their rows stay 0 here (the owners reduce them).
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < sum_chunks_.size(); ++i) {
      const std::size_t c = sum_chunks_[i];
      // Each node's force and row sum: its atoms' in atom order, whatever the threads.
      sum_nodes<kForceStride, 3>(c * kNodeChunk, std::min(model_.num_nodes, (c + 1) * kNodeChunk), partition_forces_, 0, node_slots_.size(), f_out,
                                 nodal_mass_ ? nodal_bound_.data() : nullptr, touched_.empty() ? nullptr : touched_.data());
      if (nodal_mass_) nodal_bound_of_chunk(c);
    }
  }
  // The sums over atoms and chunks, exact (ExactSum): the same bits whichever process or thread
  // adds which atom.
  sums_.energy.clear(), sums_.viscous_power.clear();
  for (std::size_t p = 0; p < partition_acc_.size(); ++p)
    if (own_rank_ < 0 || partition_rank_[p] == own_rank_)
      sums_.energy.add(partition_acc_[p].energy), sums_.viscous_power.add(partition_acc_[p].viscous_power);
  for (std::size_t c = 0; c < chunk_anp_energy_.size(); ++c)
    if (own_rank_ < 0 || chunk_rank_[c] == own_rank_) sums_.energy.add(chunk_anp_energy_[c]);
  StressPassResult r = pass_result(sums_);
  if (nodal_mass_) nodal_critical_step(r);
  return r;
}

// The minima over this process's atoms in atom order (ties of the smallest step or Jacobian go to
// the first); the sums as given.
StressPassResult InternalForces::pass_result(const PassSums& sums) const {
  const bool viscous = beta_ > 0;
  StressAccumulator total;
  for (const StressAccumulator& acc : partition_acc_) {
    if (acc.min_J < total.min_J) total.min_J = acc.min_J, total.min_J_element = acc.min_J_element;
    const double dt = viscous ? acc.dt : std::sqrt(acc.dt2);
    const double best = viscous ? total.dt : std::sqrt(total.dt2);
    if (dt < best) {
      total.dt = acc.dt, total.dt2 = acc.dt2;
      total.dt_element = acc.dt_element;
    }
  }
  StressPassResult r;
  r.strain_energy = sums.energy.value();
  r.viscous_power = sums.viscous_power.value();
  r.element_critical_step = r.critical_step = viscous ? total.dt : std::sqrt(total.dt2);
  r.limiting_element = total.dt_element;
  r.nodal_critical_step = 0;  // no bound (off, or no moving node under a tet): the element estimate alone
  r.min_jacobian = total.min_J;
  r.min_jacobian_element = total.min_J_element;
  return r;
}

// Ranks: the partitions this process runs and, per other rank, the slots of shared nodes that go
// each way. Both sides list a pair's slots node by node (ascending), each node's slots in atom
// order, so a buffer needs no index; and the ANP tiles at those nodes, ascending. The ANP J pass
// runs over the rank's own nodes, with ghost nodes exchanged after each node pass (anp_ghosts_of_rank).
void InternalForces::own_atoms(const std::vector<std::uint32_t>& tet_atom, const std::vector<std::int32_t>& atom_rank, int rank) {
  if (tet_atom.size() != model_.num_elements)
    throw InputError("decomposition", "tet_atom", std::to_string(model_.num_elements) + " tets", std::to_string(tet_atom.size()));
  if (own_rank_ >= 0) throw std::logic_error("InternalForces::own_atoms: called twice (the other ranks' slots are gone after the first)");
  own_rank_ = rank;
  partition_rank_.assign(partitions_.size(), 0);
  partition_acc_.assign(partitions_.size(), StressAccumulator{});  // the other ranks' atoms never run here: they stay empty
  std::vector<std::uint32_t> slot_partition(partition_volumes_.size()), tile_partition(anp_tiles_.size());
  for (std::size_t p = 0; p < partitions_.size(); ++p) {
    const Partition& q = partitions_[p];
    if (q.begin < q.end) partition_rank_[p] = atom_rank.at(tet_atom[q.begin]);
    for (std::size_t sl = q.slot_begin; sl < q.slot_end; ++sl) slot_partition[sl] = static_cast<std::uint32_t>(p);
    if (model_.blocks[q.block].material.anp())
      for (std::size_t t = 0; t < tiles_of(q.end - q.begin); ++t) tile_partition[q.tile_offset + t] = static_cast<std::uint32_t>(p);
  }
  sum_chunks_.clear();
  std::vector<char>& touched = touched_;  // by this rank's atoms
  touched.assign(model_.num_nodes, 0);
  for (std::size_t n = 0; n < model_.num_nodes; ++n) {
    for (std::size_t k = node_slot_first_[n]; k < node_slot_first_[n + 1]; ++k) touched[n] |= partition_rank_[slot_partition[node_slots_[k]]] == rank;
    if (touched[n] && (sum_chunks_.empty() || sum_chunks_.back() != n / kNodeChunk)) sum_chunks_.push_back(n / kNodeChunk);
  }
  node_rank_.assign(model_.num_nodes, -1);
  for (std::size_t n = 0; n < model_.num_nodes; ++n)
    if (node_slot_first_[n] < node_slot_first_[n + 1]) node_rank_[n] = partition_rank_[slot_partition[node_slots_[node_slot_first_[n]]]];
  anp_ghosts_of_rank(rank, touched, slot_partition);
  halo_.clear();
  std::vector<std::size_t> halo_of_rank;  // index in halo_ + 1, per rank
  std::vector<std::size_t> listed;        // per entry of halo_: the last node whose slots it lists
  std::vector<char> sends(partitions_.size(), 0);
  for (std::size_t n = 0; n < model_.num_nodes; ++n) {
    if (!touched[n]) continue;
    for (std::size_t k = node_slot_first_[n]; k < node_slot_first_[n + 1]; ++k) {
      const int other = partition_rank_[slot_partition[node_slots_[k]]];
      if (other == rank) continue;
      if (halo_of_rank.size() <= static_cast<std::size_t>(other)) halo_of_rank.resize(static_cast<std::size_t>(other) + 1, 0);
      std::size_t& h = halo_of_rank[static_cast<std::size_t>(other)];
      if (!h) halo_.push_back({other, {}, {}, {}, {}}), listed.push_back(n + 1), h = halo_.size();
      HaloSlots& pair = halo_[h - 1];
      if (listed[h - 1] == n) continue;  // this node's slots are listed already
      listed[h - 1] = n;
      for (std::size_t kk = node_slot_first_[n]; kk < node_slot_first_[n + 1]; ++kk) {
        const std::uint32_t sl = node_slots_[kk];
        const int owner = partition_rank_[slot_partition[sl]];
        if (owner == rank) pair.send.push_back(sl), sends[slot_partition[sl]] = 1;
        if (owner == other) pair.receive.push_back(sl);
      }
      for (std::size_t t = anp_node_tile_first_[n]; t < anp_node_tile_first_[n + 1]; ++t) {
        const std::uint32_t tile = anp_node_tiles_[t];
        const int owner = partition_rank_[tile_partition[tile]];
        if (owner == rank) pair.send_tiles.push_back(tile);
        if (owner == other) pair.receive_tiles.push_back(tile);
      }
    }
  }
  std::sort(halo_.begin(), halo_.end(), [](const HaloSlots& a, const HaloSlots& b) { return a.rank < b.rank; });
  for (HaloSlots& h : halo_)  // a tile holds several shared nodes: once each, ascending
    for (auto* tiles : {&h.send_tiles, &h.receive_tiles}) {
      std::sort(tiles->begin(), tiles->end());
      tiles->erase(std::unique(tiles->begin(), tiles->end()), tiles->end());
    }
  boundary_atoms_.clear(), interior_atoms_.clear();
  for (std::size_t p = 0; p < partitions_.size(); ++p)
    if (partition_rank_[p] == rank) (sends[p] ? boundary_atoms_ : interior_atoms_).push_back(p);
  keep_rank_slots(rank, slot_partition);
}

// Ranks: the slots this rank's atoms fill and those it receives, renumbered in their global order
// (each own atom's slots stay one run, each node's stay in atom order and each block's a range), and
// the corners of this rank's atoms' tets; the others' slots and corners are dropped (fresh arrays,
// so their capacity goes too). A node this rank touches keeps all its slots (the halo brings every
// one it does not fill); one it does not touch keeps none (sum_nodes writes 0 there).
void InternalForces::keep_rank_slots(int rank, const std::vector<std::uint32_t>& slot_partition) {
  const std::size_t slots = slot_partition.size();
  std::vector<char> kept(slots, 0);
  for (std::size_t s = 0; s < slots; ++s) kept[s] = partition_rank_[slot_partition[s]] == rank;
  for (const HaloSlots& h : halo_)
    for (std::uint32_t s : h.receive) kept[s] = 1;
  std::vector<std::uint32_t> local(slots + 1, 0);  // per global slot: how many kept slots come before it
  for (std::size_t s = 0; s < slots; ++s) local[s + 1] = local[s] + static_cast<std::uint32_t>(kept[s]);
  for (HaloSlots& h : halo_)
    for (auto* list : {&h.send, &h.receive})
      for (std::uint32_t& s : *list) s = local[s];
  for (std::size_t k = 0; k < block_slot_begin_.size(); ++k)
    block_slot_begin_[k] = local[block_slot_begin_[k]], block_slot_end_[k] = local[block_slot_end_[k]];
  std::vector<std::size_t> first(model_.num_nodes + 1, 0);
  std::vector<std::uint32_t> node_slots;
  node_slots.reserve(local[slots]);
  for (std::size_t n = 0; n < model_.num_nodes; ++n) {
    for (std::size_t k = node_slot_first_[n]; k < node_slot_first_[n + 1]; ++k)
      if (kept[node_slots_[k]]) node_slots.push_back(local[node_slots_[k]]);
    first[n + 1] = node_slots.size();
  }
  node_slot_first_ = std::move(first), node_slots_ = std::move(node_slots);
  std::size_t corners = 0;
  for (std::size_t p = 0; p < partitions_.size(); ++p)
    if (partition_rank_[p] == rank) corners += 4 * (partitions_[p].end - partitions_[p].begin);
  std::vector<std::uint16_t> tet_slot;
  tet_slot.reserve(corners);
  for (std::size_t p = 0; p < partitions_.size(); ++p) {
    Partition& q = partitions_[p];
    q.slot_begin = local[q.slot_begin], q.slot_end = local[q.slot_end];
    if (partition_rank_[p] != rank) {  // never runs here
      q.slot_end = q.slot_begin, q.corner_begin = 0;
      continue;
    }
    const auto from = tet_slot_.begin() + static_cast<std::ptrdiff_t>(q.corner_begin);
    q.corner_begin = tet_slot.size();
    tet_slot.insert(tet_slot.end(), from, from + static_cast<std::ptrdiff_t>(4 * (q.end - q.begin)));
  }
  tet_slot_ = std::move(tet_slot);
  partition_forces_ = std::vector<double>(kForceStride * local[slots], 0.0);
  partition_volumes_ = std::vector<double>(local[slots], 0.0);
}

void InternalForces::hold_own_geometry(const std::vector<TetRange>& tets) {
  if (own_rank_ < 0) throw std::logic_error("InternalForces::hold_own_geometry: before own_atoms (one process reads the model's)");
  if (holds_geometry_) return;
  if (!mass_factor_.empty())  // its per-tet arrays are then the held tets'
    throw std::logic_error("InternalForces::hold_own_geometry: after enable_mass_scaling (enable it once the tets are held)");
  // The runs split at the blocks' ends (a block's law data has its own stride).
  for (const TetRange& r : tets)
    for (std::size_t k = 0; k < model_.blocks.size(); ++k) {
      const MaterialBlock& b = model_.blocks[k];
      const std::size_t lo = std::max(r.begin, b.begin), hi = std::min(r.end, b.end);
      if (lo < hi) held_runs_.push_back({k, lo, hi, 0, 0});
    }
  std::sort(held_runs_.begin(), held_runs_.end(), [](const HeldRun& a, const HeldRun& b) { return a.begin < b.begin; });
  std::size_t count = 0, data = 0;
  for (HeldRun& r : held_runs_) {
    const MaterialBlock& b = model_.blocks[r.block];
    r.tet = count, r.data = data;
    count += r.end - r.begin;
    if (b.per_element_data()) data += b.data_stride() * (r.end - r.begin);
  }
  held_conn_.reserve(4 * count), held_grad_.reserve(9 * count), held_volume_.reserve(count), held_data_.reserve(data);
  for (const HeldRun& r : held_runs_) {
    const MaterialBlock& b = model_.blocks[r.block];
    held_conn_.insert(held_conn_.end(), model_.conn.begin() + static_cast<std::ptrdiff_t>(4 * r.begin),
                      model_.conn.begin() + static_cast<std::ptrdiff_t>(4 * r.end));
    held_grad_.insert(held_grad_.end(), model_.grad.begin() + static_cast<std::ptrdiff_t>(9 * r.begin),
                      model_.grad.begin() + static_cast<std::ptrdiff_t>(9 * r.end));
    held_volume_.insert(held_volume_.end(), model_.volume.begin() + static_cast<std::ptrdiff_t>(r.begin),
                        model_.volume.begin() + static_cast<std::ptrdiff_t>(r.end));
    if (b.per_element_data()) held_data_.insert(held_data_.end(), b.data_of(r.begin), b.data_of(r.end));
  }
  // Each own atom lies within one held run.
  for (std::size_t p = 0; p < partitions_.size(); ++p) {
    if (partition_rank_[p] != own_rank_) continue;
    Partition& q = partitions_[p];
    const auto in = std::upper_bound(held_runs_.begin(), held_runs_.end(), q.begin, [](std::size_t e, const HeldRun& r) { return e < r.begin; });
    if (in == held_runs_.begin() || std::prev(in)->end < q.end)
      throw std::logic_error("InternalForces::hold_own_geometry: tets " + std::to_string(q.begin) + "-" + std::to_string(q.end) +
                             " of this rank's atoms are not among the tets given");
    const HeldRun& r = *std::prev(in);
    q.held_tet = r.tet + (q.begin - r.begin);
    q.held_data = r.data + model_.blocks[q.block].data_stride() * (q.begin - r.begin);
  }
  holds_geometry_ = true;
}

template <class F>
void InternalForces::each_run(F f) const {
  if (!holds_geometry_) {
    for (std::size_t bi = 0; bi < model_.blocks.size(); ++bi) {
      const MaterialBlock& b = model_.blocks[bi];
      f(bi, b.begin, b.end, b.begin, b.data());
    }
    return;
  }
  for (const HeldRun& r : held_runs_) {
    const MaterialBlock& b = model_.blocks[r.block];
    f(r.block, r.begin, r.end, r.tet, b.per_element_data() ? held_data_.data() + r.data : b.data());
  }
}

void InternalForces::cell_records(const double* u, const CellSink& sink) const {
  std::vector<double> record(cell_record_width(model_), 0.0);
  each_run([&](std::size_t bi, std::size_t begin, std::size_t end, std::size_t at, const double* data) {
    const MaterialBlock& b = model_.blocks[bi];
    const double* p = b.has_stress_pass() ? block_pressure_[bi] : nullptr;  // ANP: the pass's nodal pressures
    const std::size_t stride = b.data_stride();
    for (std::size_t k = 0; k < end - begin; ++k) {
      const std::int32_t* c = tet_conn() + 4 * (at + k);
      const double* g = tet_grad() + 9 * (at + k);
      const double* d = data + stride * k;
      const Mat3 F = Mat3::Identity() + nodal_gradient(u, c, g);
      fill_cell_record(b, F, reported_cauchy_stress(b, F, c, p, rigid_node_.data(), d), d, record.data());
      sink(bi, begin + k, c, record.data());
    }
  });
}

void InternalForces::raise_to_floor(double floor2, std::vector<FloorTet>& out) {
  each_run([&](std::size_t bi, std::size_t begin, std::size_t end, std::size_t at, const double*) {
    if (!model_.blocks[bi].has_stress_pass()) return;  // no step of their own
    const double density = model_.blocks[bi].material.density();
    for (std::size_t k = 0; k < end - begin; ++k) {
      double& factor = mass_factor_[at + k];
      const double dt2 = element_dt2_[at + k];
      if (!(dt2 * factor < floor2)) continue;
      // The tet's step grows as sqrt of its mass: (rho V + dM) / (rho V) = floor^2 / dt_e^2.
      const double target = floor2 / dt2;
      const std::int32_t* c = tet_conn() + 4 * (at + k);
      out.push_back({begin + k, density * tet_volume()[at + k], factor, target, {c[0], c[1], c[2], c[3]}});
      factor = target;
    }
  });
}

std::pair<double, std::size_t> InternalForces::smallest_scaled_step(double beta) const {
  std::pair<double, std::size_t> best{std::numeric_limits<double>::infinity(), std::numeric_limits<std::size_t>::max()};
  each_run([&](std::size_t bi, std::size_t begin, std::size_t end, std::size_t at, const double*) {
    if (!model_.blocks[bi].has_stress_pass()) return;
    for (std::size_t k = 0; k < end - begin; ++k) {
      double dt = std::sqrt(element_dt2_[at + k] * mass_factor_[at + k]);
      if (beta > 0) {  // Rayleigh stiffness damping shortens the step, as the kernel computes it
        const double omega = 2.0 / dt, xi = 0.5 * beta * omega;
        dt = 2.0 / omega * (std::sqrt(1.0 + xi * xi) - xi);
      }
      if (dt < best.first) best = {dt, begin + k};
    }
  });
  return best;
}

void InternalForces::set_mass_factors(const std::vector<double>& whole) {
  if (!holds_geometry_) {
    mass_factor_ = whole;
    return;
  }
  for (const HeldRun& r : held_runs_)
    std::copy(whole.begin() + static_cast<std::ptrdiff_t>(r.begin), whole.begin() + static_cast<std::ptrdiff_t>(r.end),
              mass_factor_.begin() + static_cast<std::ptrdiff_t>(r.tet));
}

const std::int32_t* InternalForces::nodes_of_tet(std::size_t e) const {
  if (!holds_geometry_) return e < model_.num_elements && !model_.conn.empty() ? &model_.conn[4 * e] : nullptr;
  const auto in = std::upper_bound(held_runs_.begin(), held_runs_.end(), e, [](std::size_t t, const HeldRun& r) { return t < r.begin; });
  if (in == held_runs_.begin() || std::prev(in)->end <= e) return nullptr;
  return &held_conn_[4 * (std::prev(in)->tet + (e - std::prev(in)->begin))];
}

std::size_t cell_record_width(const Model& model) {
  std::size_t law = 0;
  for (const MaterialBlock& b : model.blocks) {
    std::size_t n = 0;
    for (const auto& f : b.material.type().result_fields) n += static_cast<std::size_t>(f.components);
    law = std::max(law, n);
  }
  return kCellRecordFixed + law;
}

void fill_cell_record(const MaterialBlock& b, const Mat3& F, const Mat3& s, const double* law_data, double* record) {
  const double voigt[6] = {s(0, 0), s(1, 1), s(2, 2), s(0, 1), s(1, 2), s(0, 2)};
  std::copy(voigt, voigt + 6, record);
  record[6] = von_mises(s);
  record[7] = F.row(0).dot(cofactor(F).row(0));
  if (!b.material.type().result_fields.empty()) b.material.type().result_values(b.material.law(), F, law_data, record + kCellRecordFixed);
}

// The node runs of the ANP J pass (anp_pass): where `computed` holds, in runs of consecutive nodes
// within a node chunk; where U' turns ratios into pressures: each chunk that `rank` reports whole,
// and elsewhere the runs where `read` holds.
void InternalForces::set_anp_runs(const std::vector<char>& computed, const std::vector<char>& read, int rank) {
  const auto runs = [&](const std::vector<char>& in, std::size_t c, std::vector<NodeRun>& out) {
    const std::size_t end = std::min(model_.num_nodes, (c + 1) * kNodeChunk);
    for (std::size_t n = c * kNodeChunk; n < end; ++n)
      if (in[n]) {
        std::size_t hi = n + 1;
        while (hi < end && in[hi]) ++hi;
        out.push_back({n, hi, c, false});
        n = hi;
      }
  };
  anp_runs_.clear(), anp_convert_runs_.clear();
  for (std::size_t c = 0; c < num_chunks_; ++c) {
    runs(computed, c, anp_runs_);
    if (chunk_rank_[c] == rank)
      anp_convert_runs_.push_back({c * kNodeChunk, std::min(model_.num_nodes, (c + 1) * kNodeChunk), c, true});
    else
      runs(read, c, anp_convert_runs_);
  }
  convert_energy_.assign(anp_convert_runs_.size(), 0.0);
}

// The ANP J pass of one rank (docs/design.md, "The stress pass over MPI ranks"). The rank computes
// the nodes its atoms touch (and those no stress-pass tet holds, which need nothing): their sums
// need only the halo slots' volumes. A node pass of S at such a node reads its neighbours over the
// ANP tets, so after each pass the rank receives, from their owners (node_ranks), the values of its
// ghost nodes: the neighbours it does not compute, and the nodes of the chunks whose volumetric
// energy it reports (each chunk: the rank of its first node that has an owner) that it does not
// compute. Each rank works out every rank's ghosts alike (it holds the whole model), so the lists
// of a pair agree without a message.
void InternalForces::anp_ghosts_of_rank(int rank, const std::vector<char>& touched, const std::vector<std::uint32_t>& slot_partition) {
  chunk_rank_.assign(num_chunks_, 0);
  for (std::size_t c = 0; c < num_chunks_; ++c)
    for (std::size_t n = c * kNodeChunk; n < std::min(model_.num_nodes, (c + 1) * kNodeChunk); ++n)
      if (node_rank_[n] >= 0) {
        chunk_rank_[c] = node_rank_[n];
        break;
      }
  anp_volume_atoms_.clear(), anp_ghosts_.clear();
  std::vector<char> computed(model_.num_nodes), read(model_.num_nodes);
  for (std::size_t n = 0; n < model_.num_nodes; ++n) computed[n] = read[n] = touched[n] || node_rank_[n] < 0;
  if (anp_.empty()) return set_anp_runs(computed, read, rank);
  for (std::size_t p = 0; p < partitions_.size(); ++p)
    if (partition_rank_[p] == rank && model_.blocks[partitions_[p].block].material.anp()) anp_volume_atoms_.push_back(p);
  // Per node the ranks whose atoms touch it (CSR), and with smoothing the ANP tets at it.
  std::vector<std::size_t> touch_first(model_.num_nodes + 1, 0);
  std::vector<std::int32_t> touch;
  for (std::size_t n = 0; n < model_.num_nodes; ++n) {
    const std::size_t from = touch.size();
    for (std::size_t k = node_slot_first_[n]; k < node_slot_first_[n + 1]; ++k) {
      const std::int32_t r = partition_rank_[slot_partition[node_slots_[k]]];
      if (std::find(touch.begin() + static_cast<std::ptrdiff_t>(from), touch.end(), r) == touch.end()) touch.push_back(r);
    }
    touch_first[n + 1] = touch.size();
  }
  const auto touches = [&](std::size_t n, std::int32_t r) {
    return std::find(touch.begin() + static_cast<std::ptrdiff_t>(touch_first[n]), touch.begin() + static_cast<std::ptrdiff_t>(touch_first[n + 1]),
                     r) != touch.begin() + static_cast<std::ptrdiff_t>(touch_first[n + 1]);
  };
  bool smoothing = false;
  for (const AnpBlock& a : anp_) smoothing |= model_.blocks[a.block].material.pressure_smoothing() > 0;
  std::vector<std::size_t> first(model_.num_nodes + 1, 0), tets;
  for (int fill = 0; smoothing && fill < 2; ++fill) {
    std::vector<std::size_t> next(first.begin(), first.end() - 1);
    if (fill) tets.resize(first.back());
    for (const AnpBlock& a : anp_)
      for (std::size_t e = model_.blocks[a.block].begin; e < model_.blocks[a.block].end; ++e)
        for (int k = 0; k < 4; ++k) {
          const auto n = static_cast<std::size_t>(model_.conn[4 * e + static_cast<std::size_t>(k)]);
          if (fill)
            tets[next[n]++] = e;
          else
            ++first[n + 1];
        }
    if (!fill)
      for (std::size_t n = 0; n < model_.num_nodes; ++n) first[n + 1] += first[n];
  }
  // Per node with an owner: the ranks that read it without computing it, in rank order.
  std::vector<std::vector<std::uint32_t>> send, receive;
  std::vector<std::int32_t> readers;
  for (std::size_t n = 0; n < model_.num_nodes; ++n) {
    const std::int32_t owner = node_rank_[n];
    if (owner < 0) continue;
    readers.clear();
    if (const std::int32_t r = chunk_rank_[n / kNodeChunk]; !touches(n, r)) readers.push_back(r);
    for (std::size_t t = first[n]; smoothing && t < first[n + 1]; ++t)
      for (int k = 0; k < 4; ++k) {
        const auto m = static_cast<std::size_t>(model_.conn[4 * tets[t] + static_cast<std::size_t>(k)]);
        for (std::size_t i = touch_first[m]; i < touch_first[m + 1]; ++i)
          if (!touches(n, touch[i])) readers.push_back(touch[i]);
      }
    std::sort(readers.begin(), readers.end());
    readers.erase(std::unique(readers.begin(), readers.end()), readers.end());
    for (std::int32_t r : readers) {
      const auto grow = [](std::vector<std::vector<std::uint32_t>>& lists, std::int32_t at) -> std::vector<std::uint32_t>& {
        if (lists.size() <= static_cast<std::size_t>(at)) lists.resize(static_cast<std::size_t>(at) + 1);
        return lists[static_cast<std::size_t>(at)];
      };
      if (owner == rank) grow(send, r).push_back(static_cast<std::uint32_t>(n));
      if (r == rank) grow(receive, owner).push_back(static_cast<std::uint32_t>(n)), read[n] = 1;
    }
  }
  for (std::size_t r = 0; r < std::max(send.size(), receive.size()); ++r) {
    NodeGhosts g{static_cast<int>(r), r < send.size() ? std::move(send[r]) : std::vector<std::uint32_t>{},
                 r < receive.size() ? std::move(receive[r]) : std::vector<std::uint32_t>{}};
    if (!g.send.empty() || !g.receive.empty()) anp_ghosts_.push_back(std::move(g));
  }
  set_anp_runs(computed, read, rank);
}

}  // namespace tactus::solver
