// The nodal step bound (design.md, "Stable step"; the critical time step of paper eq. 35 is
// 2 / omega_max): the per-block setup of the ANP tets' volumetric rows, and the reduction of the
// rows the stress pass scattered (step_bound.hpp) to the largest row sum / mass per node chunk and
// over the model. The per-tet rows themselves are in step_bound.hpp, inlined into every law's
// kernel.
#include "step_bound.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <utility>

#include "tactus/solver/internal_force.hpp"
#include "tactus/solver/model.hpp"

namespace tactus::solver {

namespace {

// The splitting weights eta_j = 2^(j - 6), j = 0 ... 12, of the ANP blocks' second step-bound form,
// as the factors of its change rows, 1 + 1/eta, and of its rest rows, 1 + eta (all exact in binary).
struct EtaFactors {
  double change[13], rest[13];
};
constexpr EtaFactors eta_factors() {
  EtaFactors f{};
  double eta = 1.0 / 64;
  for (int j = 0; j < 13; ++j, eta *= 2) f.change[j] = 1 + 1 / eta, f.rest[j] = 1 + eta;
  return f;
}
constexpr EtaFactors kEta = eta_factors();

// Component i of a tet's reference gradient grad_X N_k from its nine stored ones (nodes 1-3;
// node 0's is minus their sum).
double reference_gradient(const double* g, int k, int i) { return k == 0 ? -(g[i] + g[3 + i] + g[6 + i]) : g[3 * (k - 1) + i]; }

// The lengths of a tet's four reference gradients.
void reference_gradient_norms(const double* g, double norm[4]) {
  for (int k = 0; k < 4; ++k) {
    const double x = reference_gradient(g, k, 0), y = reference_gradient(g, k, 1), z = reference_gradient(g, k, 2);
    norm[k] = std::sqrt(x * x + y * y + z * z);
  }
}

}  // namespace

// The block's tets at each node, in element order: node a's are tets[first[a] .. first[a + 1]).
std::pair<std::vector<std::size_t>, std::vector<std::size_t>> block_node_tets(const Model& m, const MaterialBlock& b) {
  const std::size_t n = m.num_nodes;
  std::vector<std::size_t> first(n + 1, 0);  // the block's tets at each node
  for (std::size_t e = b.begin; e < b.end; ++e)
    for (int k = 0; k < 4; ++k) ++first[static_cast<std::size_t>(m.conn[4 * e + k]) + 1];
  for (std::size_t a = 0; a < n; ++a) first[a + 1] += first[a];
  std::vector<std::size_t> tets(first[n]), fill(first.begin(), first.end() - 1);
  for (std::size_t e = b.begin; e < b.end; ++e)
    for (int k = 0; k < 4; ++k) tets[fill[static_cast<std::size_t>(m.conn[4 * e + k])]++] = e;
  return {std::move(first), std::move(tets)};
}

// The ANP volumetric part of the nodal step bound (design.md, "Stable step"), per tet of the
// block: q_e = V0_e Q0_e / t0_e with t0_e = V0_e sum_b |grad_X N_b| (a third of the tet's reference
// surface area), Q0_e = sum_{a of e} k R0_a / (16 V_a) and R0_a = sum_{e at a} t0_e. The stress
// pass adds |d_b| q_e t_e / V0_e to node b's row (t_e the current area, from the same norms as the
// rest of the row): Cauchy-Schwarz on each nodal volume ratio with the reference areas as weights,
// so nothing of the current state but the tet's own gradients is needed.
std::vector<double> anp_step_bound_factors(const Model& m, const MaterialBlock& b, const std::vector<double>& V) {
  std::vector<double> t0(b.end - b.begin), R0(m.num_nodes, 0.0), q(b.end - b.begin);
  for (std::size_t e = b.begin; e < b.end; ++e) {
    double norm[4];
    reference_gradient_norms(&m.grad[9 * e], norm);
    t0[e - b.begin] = m.volume[e] * (norm[0] + norm[1] + norm[2] + norm[3]);
    for (int k = 0; k < 4; ++k) R0[static_cast<std::size_t>(m.conn[4 * e + k])] += t0[e - b.begin];
  }
  const double k16 = b.material.small_strain_bulk() / 16;
  for (std::size_t e = b.begin; e < b.end; ++e) {
    double Q0 = 0;
    for (int k = 0; k < 4; ++k) {
      const auto a = static_cast<std::size_t>(m.conn[4 * e + k]);
      Q0 += k16 * R0[a] / V[a];
    }
    q[e - b.begin] = m.volume[e] * Q0 / t0[e - b.begin];
  }
  return q;
}

std::vector<double> anp_rest_rows(const Model& m, const MaterialBlock& b, const std::vector<double>& V, const NodeAveraging* S) {
  const std::size_t n = m.num_nodes;
  const auto [first, tets] = block_node_tets(m, b);
  // |G0| row by row: the vector sums over a's tets, per node b of them (a itself included).
  std::vector<std::size_t> row(n + 1, 0);
  std::vector<std::int32_t> column;
  std::vector<double> norm;
  std::vector<std::array<double, 3>> sum(n, {0.0, 0.0, 0.0});
  std::vector<unsigned char> seen(n, 0);
  std::vector<std::int32_t> nodes;
  for (std::size_t a = 0; a < n; ++a) {
    nodes.clear();
    for (std::size_t t = first[a]; t < first[a + 1]; ++t) {
      const std::size_t e = tets[t];
      const double* g = &m.grad[9 * e];
      for (int k = 0; k < 4; ++k) {
        const std::int32_t node = m.conn[4 * e + k];
        if (!seen[static_cast<std::size_t>(node)]) seen[static_cast<std::size_t>(node)] = 1, nodes.push_back(node);
        for (int i = 0; i < 3; ++i) sum[static_cast<std::size_t>(node)][static_cast<std::size_t>(i)] += m.volume[e] * reference_gradient(g, k, i);
      }
    }
    std::sort(nodes.begin(), nodes.end());
    for (const std::int32_t node : nodes) {
      auto& v = sum[static_cast<std::size_t>(node)];
      column.push_back(node);
      norm.push_back(std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) / (4 * V[a]));
      v = {0.0, 0.0, 0.0}, seen[static_cast<std::size_t>(node)] = 0;
    }
    row[a + 1] = column.size();
  }
  std::vector<double> p(n, 0.0), w(n, 0.0), y(n, 0.0), rows(n, 0.0);
  for (std::size_t a = 0; a < n; ++a) p[a] = V[a] > 0 ? 1 / std::sqrt(V[a]) : 0.0;
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t j = row[a]; j < row[a + 1]; ++j) w[a] += norm[j] * p[static_cast<std::size_t>(column[j])];
  for (int pass = 0; S && pass < 2 * b.material.pressure_smoothing(); ++pass) S->apply(w.data(), y.data(), 0, n), std::swap(w, y);
  const double k = b.material.small_strain_bulk();
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t j = row[a]; j < row[a + 1]; ++j) rows[static_cast<std::size_t>(column[j])] += k * norm[j] * V[a] * w[a];
  for (std::size_t a = 0; a < n; ++a) rows[a] = p[a] > 0 ? rows[a] / p[a] : 0.0;
  return rows;
}

// Per node, the ANP block's volumetric rows of the first form at the reference state: the sum
// over the block's tets at b of |grad_X N_b| q_e t0_e, t0_e = V0_e sum_k |grad_X N_k| (what the
// stress pass adds at F = I; q the tets' factors, anp_step_bound_factors). The second form scales
// it by the tets' deformation to bound the rows now (InternalForces::compute).
std::vector<double> anp_reference_rows(const Model& m, const MaterialBlock& b, const std::vector<double>& q) {
  std::vector<double> rows(m.num_nodes, 0.0);
  for (std::size_t e = b.begin; e < b.end; ++e) {
    double norm[4];
    reference_gradient_norms(&m.grad[9 * e], norm);
    const double factor = q[e - b.begin] * m.volume[e] * (norm[0] + norm[1] + norm[2] + norm[3]);
    for (int k = 0; k < 4; ++k) rows[static_cast<std::size_t>(m.conn[4 * e + k])] += norm[k] * factor;
  }
  return rows;
}

void InternalForces::set_nodal_step_bound(const double* nodal_mass) {
  nodal_mass_ = nodal_mass;
  if (!nodal_mass_ || !node_moves_.empty()) return;  // built once (the caller may re-point it every pass)
  node_moves_.assign(model_.num_nodes, 0);
  for (std::size_t a = 0; a < model_.num_nodes; ++a)
    node_moves_[a] = !(model_.constrained[3 * a] && model_.constrained[3 * a + 1] && model_.constrained[3 * a + 2]);
  nodal_bound_.assign(model_.num_nodes, 0.0);
  chunk_bound_.assign(num_chunks_, 0.0);
  chunk_bound_node_.assign(num_chunks_, 0);
  static_assert(std::size(kEta.change) == kEtas);
  if (!anp_.empty()) {
    chunk_eta_bound_.assign(kEtas * num_chunks_, 0.0);
    chunk_eta_node_.assign(kEtas * num_chunks_, 0);
  }
}

// One node chunk of the stress pass's reduction (inside its parallel region): the largest
// row / mass of the chunk's moving nodes, and with ANP blocks the same under the second form for
// each splitting weight eta.
void InternalForces::nodal_bound_of_chunk(std::size_t c) {
  const std::size_t lo = c * kNodeChunk, hi = std::min(model_.num_nodes, lo + kNodeChunk);
  double best = 0;
  std::size_t at = 0;
  // On ranks only the nodes this process's atoms touch: at the others its rows are 0 (the plain
  // form never takes them; the eta form's row there is below the true one the owner reports, and
  // at the same node, so the MINLOC over the ranks is the same without them).
  const char* only = touched_.empty() ? nullptr : touched_.data();
  for (std::size_t n = lo; n < hi; ++n)
    if (node_moves_[n] && (!only || only[n]) && nodal_bound_[n] > best * nodal_mass_[n]) best = nodal_bound_[n] / nodal_mass_[n], at = n;
  chunk_bound_[c] = best, chunk_bound_node_[c] = at;
  if (chunk_eta_bound_.empty()) return;
  // The second form (design.md, "Stable step"): the ANP volumetric rows replaced by
  // (1 + eta) times the rest operator's plus (1 + 1/eta) times those of the change since the
  // rest state, for each eta of a fixed grid (any eta > 0 gives a bound). With C the largest
  // c^2 >= |cof F - I|_2^2 of the tiles holding the node's tets (element_loop.hpp, anp_tiles),
  // the change rows are <= C times the reference rows K, and the volumetric part of the old
  // row is >= (1 - sqrt C)^2 K, which is taken out (a hair less, for the rounding of the sums).
  double* eta_best = &chunk_eta_bound_[kEtas * c];
  std::size_t* eta_at = &chunk_eta_node_[kEtas * c];
  std::fill(eta_best, eta_best + kEtas, 0.0);
  std::fill(eta_at, eta_at + kEtas, lo);
  double plain_best = 0;  // nodes without an ANP tet: the old row, divided as above (the same bits)
  std::size_t plain_at = lo;
  for (std::size_t n = lo; n < hi; ++n) {
    if (!node_moves_[n] || (only && !only[n])) continue;
    if (anp_rest_rows_[n] == 0) {
      if (nodal_bound_[n] > plain_best * nodal_mass_[n]) plain_best = nodal_bound_[n] / nodal_mass_[n], plain_at = n;
      continue;
    }
    double C = 0;
    for (std::size_t t = anp_node_tile_first_[n]; t < anp_node_tile_first_[n + 1]; ++t) C = std::max(C, anp_tiles_[anp_node_tiles_[t]]);
    const double shrink = std::max(0.0, 1 - std::sqrt(C)), K = anp_reference_rows_[n], inv_mass = 1 / nodal_mass_[n],
                 others = (nodal_bound_[n] - (1 - 1e-12) * shrink * shrink * K) * inv_mass, changed = C * K * inv_mass,
                 rest = anp_rest_rows_[n] * inv_mass;
    for (int j = 0; j < kEtas; ++j) {
      const double row = others + kEta.change[j] * changed + kEta.rest[j] * rest;
      if (row > eta_best[j]) eta_best[j] = row, eta_at[j] = n;
    }
  }
  for (int j = 0; j < kEtas; ++j)
    if (plain_best > eta_best[j]) eta_best[j] = plain_best, eta_at[j] = plain_at;
}

// The step the bound gives, from the chunks' largest rows, into r (beside the element estimate;
// the larger of the two is the critical step).
void InternalForces::nodal_critical_step(StressPassResult& r) const { nodal_step(nodal_bound_rows(), r); }

// The chunks' largest rows, ties to the first chunk (the smallest node).
NodalBoundRows InternalForces::nodal_bound_rows() const {
  NodalBoundRows rows;
  for (std::size_t c = 0; c < chunk_bound_.size(); ++c)
    if (chunk_bound_[c] > rows.plain) rows.plain = chunk_bound_[c], rows.plain_node = chunk_bound_node_[c];
  rows.has_eta = !chunk_eta_bound_.empty();
  for (int j = 0; rows.has_eta && j < kEtas; ++j)
    for (std::size_t c = 0; c < chunk_bound_.size(); ++c)
      if (chunk_eta_bound_[kEtas * c + j] > rows.eta[j])
        rows.eta[j] = chunk_eta_bound_[kEtas * c + j], rows.eta_node[j] = chunk_eta_node_[kEtas * c + j];
  return rows;
}

void InternalForces::nodal_step(const NodalBoundRows& rows, StressPassResult& r) const {
  // omega_max^2 <= the largest row sum / mass (design.md): the chunks' largest, ties to the first.
  double omega2 = rows.plain;
  if (omega2 > 0) r.limiting_node = rows.plain_node;
  // The second form: its best eta, when it bounds omega_max^2 lower (the chunks' largest per eta).
  for (int j = 0; rows.has_eta && j < kEtas; ++j)
    if (rows.eta[j] < omega2) omega2 = rows.eta[j], r.limiting_node = rows.eta_node[j];
  if (omega2 > 0) {
    const double omega = std::sqrt(omega2), xi = 0.5 * beta_ * omega;  // with beta: the damped mode's limit
    r.nodal_critical_step = beta_ > 0 ? 2.0 / omega * (std::sqrt(1.0 + xi * xi) - xi) : 2.0 / omega;
  }
  if (r.nodal_critical_step > r.critical_step) r.critical_step = r.nodal_critical_step, r.limited_by_node = true;
}

}  // namespace tactus::solver
