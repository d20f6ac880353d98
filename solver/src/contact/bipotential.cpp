// Bi-potential frictional contact inside the explicit step (paper §2.1, eqs. 5-12): the Coulomb
// cone projection, and the Uzawa / Gauss-Seidel fixed point r = proj(tau, K_mu) on velocities over
// the constraint rows.
#include "bipotential.hpp"

#include <algorithm>
#include <cmath>

namespace tactus::solver {

namespace {

// The bi-potential augmented traction (eq. 11, docs/design.md): tau = r + rho(-u_t - (u_n + mu|u_t|) n),
// where u_n already contains h/dt.
inline Vec3 augmented_traction(const Vec3& r, const Vec3& u_t, double u_n, const Vec3& n, double mu, double rho) {
  const double ut = norm(u_t), s = u_n + mu * ut;
  return {r[0] + rho * (-u_t[0] - s * n[0]), r[1] + rho * (-u_t[1] - s * n[1]), r[2] + rho * (-u_t[2] - s * n[2])};
}

// sum_a w_a vel[node_a]: the row's relative velocity (a free rigid body's nodes: the body's).
inline Vec3 relative_velocity(const ContactRows& rows, std::size_t k, const double* vel, const RigidRows* rigid = nullptr) {
  Vec3 r{0, 0, 0};
  for (auto a = rows.start[k]; a < rows.start[k + 1]; ++a) {
    const std::int32_t node = rows.nodes[static_cast<std::size_t>(a)];
    const double wt = rows.weights[static_cast<std::size_t>(a)];
    const int b = rigid ? rigid->body(node) : -1;
    const Vec3 v = b >= 0 ? rigid->velocity(node, b) : Vec3{vel[3 * node], vel[3 * node + 1], vel[3 * node + 2]};
    for (int d = 0; d < 3; ++d) r[d] += wt * v[d];
  }
  return r;
}

// v += c w_a dr M^-1 on every dof of the row; a free rigid body's node moves its body.
inline void apply(const ContactRows& rows, std::size_t k, const Vec3& dr, double c, const double* inv_mass, double* v, RigidRows* rigid) {
  for (auto a = rows.start[k]; a < rows.start[k + 1]; ++a) {
    const std::int32_t n = rows.nodes[static_cast<std::size_t>(a)];
    const auto node = static_cast<std::size_t>(n);
    const double wt = rows.weights[static_cast<std::size_t>(a)];
    if (const int b = rigid ? rigid->body(n) : -1; b >= 0) {
      const auto bi = static_cast<std::size_t>(b);
      const Vec3 f{c * wt * dr[0], c * wt * dr[1], c * wt * dr[2]};
      const Vec3 dw = rigid->turn(b, cross(rigid->arm(n, b), f)), push = rigid->along_rail(b, f);
      for (int d = 0; d < 3; ++d) rigid->V[bi][d] += push[d] * rigid->inv_mass[bi], rigid->w[bi][d] += dw[d];
      rigid->moved[bi] = 1;
      continue;
    }
    for (int d = 0; d < 3; ++d) v[3 * node + d] += c * wt * dr[d] * inv_mass[3 * node + d];
  }
}

// n . (dv per unit reaction along n) of a row: sum_a w_a^2 n.D_a n over the deformable nodes,
// and per free rigid body |sum w_a n|^2 / m + (sum w_a r_a x n) . I^-1 (sum w_a r_a x n).
double row_compliance(const ContactRows& rows, std::size_t k, const double* n, const double* inv_mass, const RigidRows* rigid) {
  double w = 0;
  int bodies[8];
  Vec3 push[8], twist[8];
  int nb = 0;
  for (auto a = rows.start[k]; a < rows.start[k + 1]; ++a) {
    const double wt = rows.weights[static_cast<std::size_t>(a)];
    const std::int32_t node = rows.nodes[static_cast<std::size_t>(a)];
    const int b = rigid ? rigid->body(node) : -1;
    if (b < 0) {
      for (int d = 0; d < 3; ++d) w += wt * wt * n[d] * n[d] * inv_mass[3 * static_cast<std::size_t>(node) + d];
      continue;
    }
    int slot = 0;
    while (slot < nb && bodies[slot] != b) ++slot;
    if (slot == nb) {
      if (nb == 8) continue;  // (a row touches at most a slave and a triangle: never reached)
      bodies[nb] = b, push[nb] = {0, 0, 0}, twist[nb] = {0, 0, 0}, ++nb;
    }
    const Vec3 nn{n[0], n[1], n[2]};
    const Vec3 t = cross(rigid->arm(node, b), nn);
    for (int d = 0; d < 3; ++d) push[slot][d] += wt * nn[d], twist[slot][d] += wt * t[d];
  }
  for (int s = 0; s < nb; ++s) {
    const Vec3 moved = rigid->along_rail(bodies[s], push[s]);
    w += dot(moved, moved) * rigid->inv_mass[static_cast<std::size_t>(bodies[s])] + dot(twist[s], rigid->turn(bodies[s], twist[s]));
  }
  return w;
}

// Cuts the rows into at most `blocks` slabs for the parallel sweep (rows.block_start, block_rows)
// and the rows left to sweep in order after them (rows.between_blocks); returns the number of
// slabs, or 1 when the rows are swept in one sequence (few rows, a contact too narrow for slabs
// thicker than the rows' reach, or a free rigid body among them: its rows are coupled through the
// body). The slabs hold equal row counts (from a histogram, O(rows)) along the slave nodes' longest
// extent in the reference configuration, and are at least 2.5 rows' reaches thick, so that the
// even slabs' rows share no node with one another, nor the odd slabs'; a row that still does (a
// thin slab) is left to the ordered sweep. A function of the rows alone (never of the thread
// count or the motion): kept while the rows stay the same, and the same after a restart.
// `top` is the largest node id in the rows.
int cut_sweep_blocks(ContactRows& rows, const double* X, int blocks, const RigidRows* rigid, std::int32_t top) {
  const std::size_t K = rows.size();
  blocks = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(std::max(blocks, 1)), K / ContactSettings::kMinRowsPerSweepBlock));
  if (blocks <= 1 || !X) return 1;
  // The same rows as at the last cut (their nodes, in the same order), asked for the same number
  // of slabs: the same cut, kept (most steps; the rows change when the search is rebuilt).
  if (blocks == rows.cut_asked && rows.start == rows.cut_start && rows.nodes == rows.cut_nodes) return rows.cut_blocks;
  rows.cut_asked = blocks, rows.cut_start = rows.start, rows.cut_nodes = rows.nodes, rows.cut_blocks = 1;
  if (rigid)
    for (const std::int32_t node : rows.nodes)
      if (rigid->body(node) >= 0) return 1;
  auto at = [&](std::int32_t node, std::size_t d) { return X[3 * static_cast<std::size_t>(node) + d]; };
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (std::size_t k = 0; k < K; ++k)
    for (std::size_t d = 0; d < 3; ++d) lo[d] = std::min(lo[d], at(rows.slave(k), d)), hi[d] = std::max(hi[d], at(rows.slave(k), d));
  std::size_t axis = 0;
  for (std::size_t d = 1; d < 3; ++d)
    if (hi[d] - lo[d] > hi[axis] - lo[axis]) axis = d;
  double reach = 0;  // how far along the axis a row's nodes lie from its slave node
  for (std::size_t k = 0; k < K; ++k)
    for (auto a = rows.start[k] + 1; a < rows.start[k + 1]; ++a)
      reach = std::max(reach, std::abs(at(rows.nodes[static_cast<std::size_t>(a)], axis) - at(rows.slave(k), axis)));
  const double extent = hi[axis] - lo[axis];
  if (!(extent > 0)) return 1;
  if (reach > 0) blocks = static_cast<int>(std::min<double>(blocks, std::floor(extent / (2.5 * reach))));
  if (blocks <= 1) return 1;
  // Equal-count slabs: a histogram of 64 bins per slab, each bin given to the slab its first row
  // falls in by rank.
  const std::size_t bins = 64 * static_cast<std::size_t>(blocks);
  const double per_length = static_cast<double>(bins) / extent;
  auto bin_of = [&](std::size_t k) { return std::min(bins - 1, static_cast<std::size_t>((at(rows.slave(k), axis) - lo[axis]) * per_length)); };
  std::vector<std::int32_t>& row_block = rows.row_block;
  row_block.assign(bins, 0);
  for (std::size_t k = 0; k < K; ++k) ++row_block[bin_of(k)];
  std::size_t before = 0;
  for (std::size_t b = 0; b < bins; ++b) {
    const std::size_t count = static_cast<std::size_t>(row_block[b]);
    row_block[b] = static_cast<std::int32_t>(before * static_cast<std::size_t>(blocks) / K);
    before += count;
  }
  row_block.resize(bins + K);  // then each row's slab after the bins'
  for (std::size_t k = 0; k < K; ++k) row_block[bins + k] = row_block[bin_of(k)];
  // Per parity, each node's slab: the one slab of that parity whose rows touch it, or -2 when rows
  // of two such slabs do; those rows go to the ordered sweep.
  std::vector<std::int32_t>& node_block = rows.node_block;
  if (node_block.size() <= static_cast<std::size_t>(top)) node_block.resize(static_cast<std::size_t>(top) + 1, -1);
  auto nodes_of = [&](std::size_t k, auto&& f) {
    for (auto a = rows.start[k]; a < rows.start[k + 1]; ++a) f(node_block[static_cast<std::size_t>(rows.nodes[static_cast<std::size_t>(a)])]);
  };
  for (std::int32_t parity = 0; parity < 2; ++parity) {
    for (std::size_t k = 0; k < K; ++k)
      if (const std::int32_t b = row_block[bins + k]; b % 2 == parity)
        nodes_of(k, [b](std::int32_t& owner) { owner = owner == -1 || owner == b ? b : -2; });
    for (std::size_t k = 0; k < K; ++k) {
      bool shared = false;
      if (row_block[bins + k] % 2 == parity) nodes_of(k, [&shared](std::int32_t& owner) { shared = shared || owner == -2; });
      if (shared) row_block[bins + k] = -1;
    }
    for (const std::int32_t node : rows.nodes) node_block[static_cast<std::size_t>(node)] = -1;
  }
  rows.block_start.assign(static_cast<std::size_t>(blocks) + 1, 0);
  rows.between_blocks.clear();
  for (std::size_t k = 0; k < K; ++k) {
    if (row_block[bins + k] < 0)
      rows.between_blocks.push_back(static_cast<std::int32_t>(k));
    else
      ++rows.block_start[static_cast<std::size_t>(row_block[bins + k]) + 1];
  }
  for (int b = 0; b < blocks; ++b) rows.block_start[static_cast<std::size_t>(b) + 1] += rows.block_start[static_cast<std::size_t>(b)];
  rows.block_rows.resize(static_cast<std::size_t>(rows.block_start.back()));
  std::copy(rows.block_start.begin(), rows.block_start.end() - 1, row_block.begin());  // the bins' slots, free now: fill cursors
  for (std::size_t k = 0; k < K; ++k)
    if (const std::int32_t b = row_block[bins + k]; b >= 0)
      rows.block_rows[static_cast<std::size_t>(row_block[static_cast<std::size_t>(b)]++)] = static_cast<std::int32_t>(k);
  rows.cut_blocks = blocks;
  return blocks;
}

}  // namespace

void WarmStart::find_written() {
  written.clear();
  for (std::size_t p = 0; p < reaction.size(); ++p)
    for (std::size_t i = 0; 3 * i < reaction[p].size(); ++i)
      if (reaction[p][3 * i] != 0 || reaction[p][3 * i + 1] != 0 || reaction[p][3 * i + 2] != 0)
        written.push_back(static_cast<std::int32_t>(p)), written.push_back(static_cast<std::int32_t>(i));
}

Vec3 RigidRows::arm(std::int32_t node, int b) const {
  const auto i = 3 * static_cast<std::size_t>(node);
  const Vec3& c = centre[static_cast<std::size_t>(b)];
  return {X[i] + u[i] - c[0], X[i + 1] + u[i + 1] - c[1], X[i + 2] + u[i + 2] - c[2]};
}

Vec3 RigidRows::velocity(std::int32_t node, int b) const {
  const Vec3 r = arm(node, b), wr = cross(w[static_cast<std::size_t>(b)], r);
  const Vec3& v = V[static_cast<std::size_t>(b)];
  return {v[0] + wr[0], v[1] + wr[1], v[2] + wr[2]};
}

Vec3 RigidRows::turn(int b, const Vec3& m) const {
  const auto& I = inv_inertia[static_cast<std::size_t>(b)];
  return {I[0] * m[0] + I[1] * m[1] + I[2] * m[2], I[3] * m[0] + I[4] * m[1] + I[5] * m[2], I[6] * m[0] + I[7] * m[1] + I[8] * m[2]};
}

Vec3 coulomb_cone_projection(const Vec3& tau, const Vec3& n, double mu) {
  const double tn = dot(tau, n);
  const Vec3 tt{tau[0] - tn * n[0], tau[1] - tn * n[1], tau[2] - tn * n[2]};
  const double tt_norm = norm(tt);
  if (tn >= 0 && tt_norm <= mu * tn) return tau;    // inside the cone: stick (tn >= 0 also for mu = 0)
  if (mu * tt_norm <= -tn) return {0.0, 0.0, 0.0};  // polar cone: separation
  const double rn = (tn + mu * tt_norm) / (1.0 + mu * mu);
  const double s = tt_norm > 0 ? mu * rn / tt_norm : 0.0;
  return {rn * n[0] + s * tt[0], rn * n[1] + s * tt[1], rn * n[2] + s * tt[2]};
}

LocalContactResult bipotential_local_solve(const Vec3& u_free, const Vec3& n, double w, double mu, double tolerance, int max_iterations) {
  LocalContactResult out;
  const double rho = 1.0 / w;
  Vec3& r = out.reaction;
  for (int it = 1; it <= max_iterations; ++it) {
    const Vec3 u{u_free[0] + w * r[0], u_free[1] + w * r[1], u_free[2] + w * r[2]};
    const double un = dot(u, n);
    const Vec3 ut{u[0] - un * n[0], u[1] - un * n[1], u[2] - un * n[2]};
    const Vec3 next = coulomb_cone_projection(augmented_traction(r, ut, un, n, mu, rho), n, mu);
    const double change = norm(next - r);
    r = next;
    out.iterations = it;
    if (change <= tolerance * norm(r)) break;
  }
  return out;
}

namespace {

Vec3 row_normal(const ContactRows& rows, std::size_t k) { return Vec3{rows.normal[3 * k], rows.normal[3 * k + 1], rows.normal[3 * k + 2]}; }
Vec3 row_reaction(const ContactRows& rows, std::size_t k) { return Vec3{rows.reaction[3 * k], rows.reaction[3 * k + 1], rows.reaction[3 * k + 2]}; }

// A slave node with two rows (in a concave corner) keeps its first row's warm start.
bool first_of_node(const ContactRows& rows, std::size_t k) {
  return k == 0 || rows.pair[k - 1] != rows.pair[k] || rows.slave_index[k - 1] != rows.slave_index[k];
}

// Warm start: the previous step's reaction of the same slave node, projected on the new cone and
// applied to v; the previous step's entries are then cleared.
void warm_start(ContactRows& rows, double* v, WarmStart& last, const RowSolveInput& in) {
  const auto& pairs = *in.pairs;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    if (!first_of_node(rows, k)) continue;
    const std::size_t pi = static_cast<std::size_t>(rows.pair[k]);
    const double* prev = &last.reaction[pi][3 * static_cast<std::size_t>(rows.slave_index[k])];
    if (prev[0] == 0 && prev[1] == 0 && prev[2] == 0) continue;
    const Vec3 r0 = coulomb_cone_projection({prev[0], prev[1], prev[2]}, row_normal(rows, k), pairs[pi].friction);
    for (int d = 0; d < 3; ++d) rows.reaction[3 * k + d] = r0[d];
    apply(rows, k, r0, in.velocity_per_force, in.inv_mass, v, in.rigid);
  }
  for (std::size_t i = 0; i < last.written.size(); i += 2)  // the previous step's entries (the rest are 0)
    std::fill_n(&last.reaction[static_cast<std::size_t>(last.written[i])][3 * static_cast<std::size_t>(last.written[i + 1])], 3, 0.0);
  last.written.clear();
}

// This step's reactions, per pair and slave node, for the next step's warm start.
void keep_for_warm_start(const ContactRows& rows, WarmStart& last) {
  for (std::size_t k = 0; k < rows.size(); ++k) {
    if (!first_of_node(rows, k)) continue;
    double* prev = &last.reaction[static_cast<std::size_t>(rows.pair[k])][3 * static_cast<std::size_t>(rows.slave_index[k])];
    for (int d = 0; d < 3; ++d) prev[d] = rows.reaction[3 * k + d];
    last.written.push_back(rows.pair[k]), last.written.push_back(rows.slave_index[k]);
  }
}

// The Uzawa iterations of one step (eqs. 11-12 with rho = 1/w: one iteration is exact for an
// isolated frictionless node), Gauss-Seidel over the rows, in row order or slab by slab.
class UzawaSweep {
 public:
  UzawaSweep(ContactRows& rows, double* v, const RowSolveInput& in, ContactStepReport& rep)
      : rows_(rows),
        v_(v),
        in_(in),
        rigid_(in.rigid),
        deepest_allowed_(-in.settings->recovery_speed * in.dt),
        inv_dt_(in.dt > 0 ? 1.0 / in.dt : 0.0),
        skip_unchanged_(in.rigid == nullptr) {
    // The gap folded into the normal velocity closes a row's gap within the step. A gap the
    // previous step's correction left is zero (to the Uzawa tolerance); one below -recovery_speed dt
    // is a penetration that step did not make (a node that slid back over a master's edge, where it
    // was held only from in front; a row that just appeared) and would be closed at depth / dt:
    // 0.1 mm at dt = 4e-8 s is 2,500 m/s, an explosion. Such a row is pushed out at recovery_speed
    // and cannot go deeper; the ordinary approach of a node within one step is unchanged.
    for (std::size_t k = 0; k < rows.size(); ++k)
      if (rows.gap[k] < deepest_allowed_) {
        ++rep.recovering;
        if (rows.gap[k] < rep.deepest_gap) rep.deepest_gap = rows.gap[k], rep.deepest_node = rows.slave(k);
      }
  }

  // Sweeps until the largest change is within the tolerance of the largest reaction; the number
  // of sweeps and that ratio into rep.
  void run(ContactStepReport& rep);

 private:
  // Row k one step; its change and its new reaction's size.
  std::pair<double, double> update(std::size_t k);
  // update(k) unless the row cannot change (below); `now` orders the visits.
  std::pair<double, double> visit(std::size_t k, std::int64_t now);
  void sweep(const std::int32_t* order, std::size_t n, std::size_t position, double& max_dr, double& max_r);
  // The slabs and the per-node tables of the skip logic; the number of slabs.
  int prepare(ContactStepReport& rep);
  void focus(double max_r);

  ContactRows& rows_;
  double* v_;
  const RowSolveInput& in_;
  RigidRows* rigid_;
  const double deepest_allowed_, inv_dt_;
  // A row whose last update changed nothing and none of whose nodes' velocities changed since
  // would change nothing again (update is a function of its reaction and those velocities): it
  // is skipped, with the same result (the same bits). Most rows are open (on the hand-block demo
  // 94 % of the updates change nothing); a third of the updates are skipped there, those of open
  // rows away from the moving ones (a coarse master's node is in many rows). Times order them:
  // sweep `it`, position p in the sweep (slabs of one parity share no node, so their rows'
  // positions need not follow the threads' order), it (K + 1) + p; the focused sweeps at
  // it (K + 1) + K. Not with free rigid bodies, whose rows all move through the body.
  const bool skip_unchanged_;
  std::int64_t sweep_start_ = 0;  // it (K + 1)
};

std::pair<double, double> UzawaSweep::update(std::size_t k) {
  const double w = rows_.compliance[k];
  if (!(w > 0)) return {0.0, 0.0};
  const Vec3 n = row_normal(rows_, k);
  const double mu = (*in_.pairs)[static_cast<std::size_t>(rows_.pair[k])].friction;
  const Vec3 uu = relative_velocity(rows_, k, v_, rigid_);
  const double un_vel = dot(uu, n);
  const Vec3 ut{uu[0] - un_vel * n[0], uu[1] - un_vel * n[1], uu[2] - un_vel * n[2]};
  const double un = un_vel + std::max(rows_.gap[k], deepest_allowed_) * inv_dt_;  // the gap folded in (above)
  double* r = &rows_.reaction[3 * k];
  const Vec3 rk{r[0], r[1], r[2]};
  const Vec3 next = coulomb_cone_projection(augmented_traction(rk, ut, un, n, mu, 1.0 / w), n, mu);
  const Vec3 dr{next[0] - rk[0], next[1] - rk[1], next[2] - rk[2]};
  const double drn = norm(dr);
  if (drn > 0) {
    for (int d = 0; d < 3; ++d) r[d] = next[d];
    apply(rows_, k, dr, in_.velocity_per_force, in_.inv_mass, v_, rigid_);
  }
  return {drn, norm(next)};
}

std::pair<double, double> UzawaSweep::visit(std::size_t k, std::int64_t now) {
  if (!skip_unchanged_) return update(k);
  std::vector<std::int64_t>& node_time = rows_.node_time;
  if (rows_.quiet[k]) {
    bool moved = false;
    for (auto a = rows_.start[k]; a < rows_.start[k + 1] && !moved; ++a)
      moved = node_time[static_cast<std::size_t>(rows_.nodes[static_cast<std::size_t>(a)])] >= rows_.row_time[k];
    if (!moved) return {0.0, norm(row_reaction(rows_, k))};
  }
  const auto result = update(k);
  rows_.row_time[k] = now, rows_.quiet[k] = result.first == 0;
  if (result.first > 0)
    for (auto a = rows_.start[k]; a < rows_.start[k + 1]; ++a) node_time[static_cast<std::size_t>(rows_.nodes[static_cast<std::size_t>(a)])] = now;
  return result;
}

void UzawaSweep::sweep(const std::int32_t* order, std::size_t n, std::size_t position, double& max_dr, double& max_r) {
  for (std::size_t i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(order ? order[i] : static_cast<std::int32_t>(i));
    const auto [drn, rn] = visit(k, sweep_start_ + static_cast<std::int64_t>(position + i));
    rows_.change[k] = drn;
    max_dr = std::max(max_dr, drn);
    max_r = std::max(max_r, rn);
  }
}

int UzawaSweep::prepare(ContactStepReport& rep) {
  const std::size_t K = rows_.size();
  rows_.change.assign(K, 0.0);
  // The sweep: in row order, or slab by slab in parallel, the even slabs then the odd ones (slabs
  // of one parity share no node, so each is its own Gauss-Seidel sweep and the result does not
  // depend on which thread took which), then the rows left over in order.
  std::int32_t top = -1;  // the largest node id in the rows: the size of the per-node tables below
  for (const std::int32_t node : rows_.nodes) top = std::max(top, node);
  const int blocks = cut_sweep_blocks(rows_, in_.X, in_.settings->sweep_blocks, rigid_, top);
  rep.sweep_blocks = blocks;
  rep.rows_in_order = blocks > 1 ? rows_.between_blocks.size() : K;
  rows_.block_change.assign(2 * static_cast<std::size_t>(blocks), 0.0);
  if (skip_unchanged_) {
    if (rows_.node_time.size() <= static_cast<std::size_t>(top)) rows_.node_time.resize(static_cast<std::size_t>(top) + 1);
    for (const std::int32_t node : rows_.nodes) rows_.node_time[static_cast<std::size_t>(node)] = -1;
    rows_.row_time.assign(K, -1);
    rows_.quiet.assign(K, 0);
  }
  return blocks;
}

// Rows that are nearly one constraint (a light skin node pressed between a heavier one and the
// block: their coupling c gives the sweep a contraction of c^2, 0.993 seen) creep while the rest
// has long converged. Every kFocusEvery sweeps without convergence, the rows that still changed
// are swept alone, up to kFocusSweeps times (a few rows: cheap), until their change is 100 times
// below the tolerance; the full sweeps then go on. A step converged within kFocusEvery sweeps is
// unchanged by this.
constexpr int kFocusEvery = 30, kFocusSweeps = 2000;

void UzawaSweep::focus(double max_r) {
  const double tolerance = in_.settings->tolerance;
  rows_.creeping.clear();
  for (std::size_t k = 0; k < rows_.size(); ++k)
    if (rows_.change[k] > tolerance * max_r) rows_.creeping.push_back(k);
  for (int pass = 0; pass < kFocusSweeps; ++pass) {
    double focus_dr = 0;
    for (std::size_t k : rows_.creeping) focus_dr = std::max(focus_dr, visit(k, sweep_start_ + static_cast<std::int64_t>(rows_.size())).first);
    if (focus_dr <= 1e-2 * tolerance * max_r) break;
  }
}

void UzawaSweep::run(ContactStepReport& rep) {
  const std::size_t K = rows_.size();
  const int blocks = prepare(rep);
  const auto sweep_length = static_cast<std::int64_t>(K) + 1;
  double residual = 0;
  int it = 0;
  for (it = 1; it <= in_.settings->max_iterations; ++it) {
    double max_dr = 0, max_r = 0;
    sweep_start_ = it * sweep_length;
    if (blocks == 1) {
      sweep(nullptr, K, 0, max_dr, max_r);
    } else {
      double* block_change = rows_.block_change.data();
      for (int parity = 0; parity < 2; ++parity) {  // the even slabs, then the odd ones
#pragma omp parallel for num_threads(in_.threads) schedule(dynamic, 1)
        for (int b = parity; b < blocks; b += 2) {
          const auto first = static_cast<std::size_t>(rows_.block_start[static_cast<std::size_t>(b)]);
          const auto last_row = static_cast<std::size_t>(rows_.block_start[static_cast<std::size_t>(b) + 1]);
          double dr = 0, r = 0;
          sweep(rows_.block_rows.data() + first, last_row - first, first, dr, r);
          block_change[2 * b] = dr, block_change[2 * b + 1] = r;
        }
      }
      for (int b = 0; b < blocks; ++b) max_dr = std::max(max_dr, block_change[2 * b]), max_r = std::max(max_r, block_change[2 * b + 1]);
      sweep(rows_.between_blocks.data(), rows_.between_blocks.size(), rows_.block_rows.size(), max_dr, max_r);
    }
    residual = max_r > 0 ? max_dr / max_r : 0.0;
    if (residual <= in_.settings->tolerance) break;
    if (it % kFocusEvery == 0) focus(max_r);
  }
  rep.iterations = std::min(it, in_.settings->max_iterations);
  rep.residual = residual;
  rep.converged = residual <= in_.settings->tolerance;
}

// Row k's share of the report: its status and resultants, and the work of its reaction
// (trapezoid halves over du^{n-1/2}, du^{n+1/2}), its prescribed dofs' share to their supports.
void report_row(ContactRows& rows, std::size_t k, const double* v, const RowSolveInput& in, double max_rn, ContactStepReport& rep) {
  const Vec3 r = row_reaction(rows, k);
  const Vec3 n = row_normal(rows, k);
  const double rn = dot(r, n);
  if (!(rn > 1e-12 * max_rn) || max_rn == 0) {
    rows.status[k] = ContactStatus::open;
    return;
  }
  const Vec3 rt{r[0] - rn * n[0], r[1] - rn * n[1], r[2] - rn * n[2]};
  const ContactPair& pair = (*in.pairs)[static_cast<std::size_t>(rows.pair[k])];
  rows.status[k] = norm(rt) < pair.friction * rn * (1 - 1e-6) ? ContactStatus::stick : ContactStatus::slip;
  ++rep.active;
  (rows.status[k] == ContactStatus::stick ? rep.sticking : rep.slipping)++;
  if (!pair.self_contact)  // a self-contact reaction is internal to its body
    for (int d = 0; d < 3; ++d) rep.force[d] += pair.report_sign * r[d];
  rep.normal_force += rn;
  if (!in.per_pair) rep.area += (pair.self_contact ? 0.5 : 1.0) * rows.area[k];  // both sides of a self-contact are slaves
  const double pressure = rn / rows.area[k];
  if (pressure > rep.peak_pressure) rep.peak_pressure = pressure, rep.peak_node = rows.slave(k);
  if (in.per_pair) {
    PairStepReport& p = (*in.per_pair)[static_cast<std::size_t>(rows.pair[k])];
    for (int d = 0; d < 3; ++d) p.force[d] += r[d];
    p.normal_force += rn, p.area += (pair.self_contact ? 0.5 : 1.0) * rows.area[k], p.peak_pressure = std::max(p.peak_pressure, pressure), ++p.active;
  }
  const Vec3 u_new = relative_velocity(rows, k, v), u_old = relative_velocity(rows, k, in.v_old);
  const double un_new = dot(u_new, n), un_old = dot(u_old, n);
  rep.normal_work_forward += in.dt * rn * un_new;
  rep.normal_work_back += in.dt_prev * rn * un_old;
  rep.friction_work_forward += in.dt * (dot(r, u_new) - rn * un_new);
  rep.friction_work_back += in.dt_prev * (dot(r, u_old) - rn * un_old);
  for (auto a = rows.start[k]; a < rows.start[k + 1]; ++a)
    for (int d = 0; d < 3; ++d) {
      const std::size_t dof = 3 * static_cast<std::size_t>(rows.nodes[static_cast<std::size_t>(a)]) + d;
      if (in.inv_mass[dof] != 0 || (in.rigid && in.rigid->body(rows.nodes[static_cast<std::size_t>(a)]) >= 0))
        continue;  // a prescribed dof: its support takes this share
      const double support = -rows.weights[static_cast<std::size_t>(a)] * r[d];
      rep.support_work_forward += in.dt * support * v[dof];
      rep.support_work_back += in.dt_prev * support * in.v_old[dof];
    }
}

// The step's report over all rows; the area per [[contact]] entry is its larger pass's (both
// passes see one interface).
void report_rows(ContactRows& rows, const double* v, const RowSolveInput& in, ContactStepReport& rep) {
  double max_rn = 0;
  if (in.per_pair) std::fill(in.per_pair->begin(), in.per_pair->end(), PairStepReport{});
  for (std::size_t k = 0; k < rows.size(); ++k) max_rn = std::max(max_rn, dot(row_reaction(rows, k), row_normal(rows, k)));
  for (std::size_t k = 0; k < rows.size(); ++k) report_row(rows, k, v, in, max_rn, rep);
  if (!in.per_pair) return;
  const auto& pairs = *in.pairs;
  const std::vector<PairStepReport>& per_pair = *in.per_pair;
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    bool larger = true;
    for (std::size_t q = 0; q < pairs.size(); ++q)
      if (q != p && pairs[q].entry == pairs[p].entry && (per_pair[q].area > per_pair[p].area || (per_pair[q].area == per_pair[p].area && q < p)))
        larger = false;
    if (larger) rep.area += per_pair[p].area;
  }
}

}  // namespace

ContactStepReport solve_rows(ContactRows& rows, double* v, WarmStart& last, const RowSolveInput& in) {
  ContactStepReport rep;
  const std::size_t K = rows.size();
  rep.candidates = K;
  rows.reaction.assign(3 * K, 0.0);
  rows.compliance.assign(K, 0.0);
  rows.status.assign(K, ContactStatus::open);
  if (K == 0) return rep;
  // Compliances: w = c sum_a w_a^2 n.D_a n, D the inverse masses (0 on prescribed dofs), with the
  // rigid bodies' coupled terms (row_compliance).
  const double c = in.velocity_per_force;
#pragma omp parallel for num_threads(in.threads) schedule(static) if (K >= 1024)
  for (std::size_t k = 0; k < K; ++k) rows.compliance[k] = c * row_compliance(rows, k, &rows.normal[3 * k], in.inv_mass, in.rigid);
  warm_start(rows, v, last, in);
  UzawaSweep sweep(rows, v, in, rep);
  sweep.run(rep);
  keep_for_warm_start(rows, last);
  if (in.rigid)  // the rigid bodies' nodes in the rows take their bodies' velocities (for the work below)
    for (std::size_t a = 0; a < rows.nodes.size(); ++a)
      if (const int b = in.rigid->body(rows.nodes[a]); b >= 0) {
        const Vec3 vb = in.rigid->velocity(rows.nodes[a], b);
        for (int d = 0; d < 3; ++d) v[3 * static_cast<std::size_t>(rows.nodes[a]) + static_cast<std::size_t>(d)] = vb[static_cast<std::size_t>(d)];
      }
  report_rows(rows, v, in, rep);
  return rep;
}

}  // namespace tactus::solver
