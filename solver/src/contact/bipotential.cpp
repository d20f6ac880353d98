// Bi-potential frictional contact inside the explicit step (paper §2.1, eqs. 5-12): detection
// with a uniform grid over the master triangles, closest point and gap per slave node, and the
// Uzawa / Gauss-Seidel fixed point r = proj(tau, K_mu) on velocities.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/solver/contact.hpp"
#include "tactus/solver/model.hpp"

namespace tactus::solver {

namespace {

using V3 = std::array<double, 3>;
inline V3 sub(const double* a, const double* b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline V3 cross(const V3& a, const V3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double norm(const V3& a) { return std::sqrt(dot(a, a)); }

// The bi-potential augmented traction (eq. 11, docs/design.md): tau = r + rho(-u_t - (u_n + mu|u_t|) n),
// where u_n already contains h/dt.
inline V3 augmented_traction(const V3& r, const V3& u_t, double u_n, const V3& n, double mu, double rho) {
  const double ut = norm(u_t), s = u_n + mu * ut;
  return {r[0] + rho * (-u_t[0] - s * n[0]), r[1] + rho * (-u_t[1] - s * n[1]), r[2] + rho * (-u_t[2] - s * n[2])};
}

}  // namespace

V3 coulomb_cone_projection(const V3& tau, const V3& n, double mu) {
  const double tn = dot(tau, n);
  const V3 tt{tau[0] - tn * n[0], tau[1] - tn * n[1], tau[2] - tn * n[2]};
  const double tt_norm = norm(tt);
  if (tn >= 0 && tt_norm <= mu * tn) return tau;  // inside the cone: stick (tn >= 0 also for mu = 0)
  if (mu * tt_norm <= -tn) return {0.0, 0.0, 0.0};  // polar cone: separation
  const double rn = (tn + mu * tt_norm) / (1.0 + mu * mu);
  const double s = tt_norm > 0 ? mu * rn / tt_norm : 0.0;
  return {rn * n[0] + s * tt[0], rn * n[1] + s * tt[1], rn * n[2] + s * tt[2]};
}

LocalContactResult bipotential_local_solve(const V3& u_free, const V3& n, double w, double mu, double tolerance,
                                           int max_iterations) {
  LocalContactResult out;
  const double rho = 1.0 / w;
  V3& r = out.reaction;
  for (int it = 1; it <= max_iterations; ++it) {
    const V3 u{u_free[0] + w * r[0], u_free[1] + w * r[1], u_free[2] + w * r[2]};
    const double un = dot(u, n);
    const V3 ut{u[0] - un * n[0], u[1] - un * n[1], u[2] - un * n[2]};
    const V3 next = coulomb_cone_projection(augmented_traction(r, ut, un, n, mu, rho), n, mu);
    const double change = norm(sub(next.data(), r.data()));
    r = next;
    out.iterations = it;
    if (change <= tolerance * norm(r)) break;
  }
  return out;
}

void ContactState::clear() {
  pair.clear(), slave.clear(), triangle.clear(), slave_index.clear(), weights.clear(), normal.clear(), gap.clear();
  reaction.clear(), compliance.clear(), area.clear(), status.clear();
}

ContactSolver::ContactSolver(const Model& model)
    : model_(model), pairs_(model.contact_pairs), settings_(model.contact_settings) {
  x_.resize(3 * model.num_nodes);
  for (const auto& p : pairs_) last_reaction_.emplace_back(3 * p.slave_nodes.size(), 0.0);
}

void ContactSolver::build_grid(const ContactPair& p, const double* x, double margin) {
  Grid& g = grid_;
  const std::size_t T = p.master_triangles.size() / 3;
  double lo[3], hi[3];
  for (int c = 0; c < 3; ++c) lo[c] = std::numeric_limits<double>::infinity(), hi[c] = -lo[c];
  for (std::int32_t v : p.master_triangles)
    for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], x[3 * v + c]), hi[c] = std::max(hi[c], x[3 * v + c]);
  for (int c = 0; c < 3; ++c) lo[c] -= margin, hi[c] += margin;
  // Cells about one master edge wide, at most ~8 per triangle (a flat surface in a large box).
  double cell = std::max(p.master_edge, 2 * margin);
  const double budget = 8.0 * static_cast<double>(T) + 64;
  while ((std::ceil((hi[0] - lo[0]) / cell) * std::ceil((hi[1] - lo[1]) / cell) * std::ceil((hi[2] - lo[2]) / cell)) > budget)
    cell *= 1.26;
  g.cell = cell;
  for (int c = 0; c < 3; ++c) g.lo[c] = lo[c], g.n[c] = std::max(1, static_cast<int>(std::ceil((hi[c] - lo[c]) / cell)));
  const std::size_t cells = static_cast<std::size_t>(g.n[0]) * g.n[1] * g.n[2];
  g.count.assign(cells + 1, 0);
  g.box.resize(T);
  g.normal.resize(4 * T);
  auto cell_of = [&](double v, int c) { return std::clamp(static_cast<int>((v - g.lo[c]) / g.cell), 0, g.n[c] - 1); };
  for (std::size_t t = 0; t < T; ++t) {
    double a[3], b[3];
    for (int c = 0; c < 3; ++c) a[c] = std::numeric_limits<double>::infinity(), b[c] = -a[c];
    for (int k = 0; k < 3; ++k) {
      const double* xv = x + 3 * p.master_triangles[3 * t + k];
      for (int c = 0; c < 3; ++c) a[c] = std::min(a[c], xv[c]), b[c] = std::max(b[c], xv[c]);
    }
    auto& bx = g.box[t];
    for (int c = 0; c < 3; ++c) bx[c] = cell_of(a[c] - margin, c), bx[3 + c] = cell_of(b[c] + margin, c);
    const std::int32_t* tri = &p.master_triangles[3 * t];
    const double* x0 = x + 3 * tri[0];
    const V3 nn = cross(sub(x + 3 * tri[1], x0), sub(x + 3 * tri[2], x0));
    const double twice_area = norm(nn);
    const double inv = twice_area > 0 ? 1.0 / twice_area : 0.0;
    for (int c = 0; c < 3; ++c) g.normal[4 * t + c] = nn[c] * inv;
    g.normal[4 * t + 3] = inv;
    for (int k = bx[2]; k <= bx[5]; ++k)
      for (int j = bx[1]; j <= bx[4]; ++j)
        for (int i = bx[0]; i <= bx[3]; ++i) ++g.count[(static_cast<std::size_t>(k) * g.n[1] + j) * g.n[0] + i + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) g.count[c + 1] += g.count[c];
  g.start.assign(g.count.begin(), g.count.end());
  g.items.resize(static_cast<std::size_t>(g.count[cells]));
  for (std::size_t t = 0; t < T; ++t) {
    const auto& bx = g.box[t];
    for (int k = bx[2]; k <= bx[5]; ++k)
      for (int j = bx[1]; j <= bx[4]; ++j)
        for (int i = bx[0]; i <= bx[3]; ++i)
          g.items[static_cast<std::size_t>(g.start[(static_cast<std::size_t>(k) * g.n[1] + j) * g.n[0] + i]++)] = static_cast<std::int32_t>(t);
  }
  // start[] was advanced to each cell's end: cell c spans [count[c], start[c]).
}

void ContactSolver::detect(const double* u) {
  state_.clear();
  const std::size_t ndof = 3 * model_.num_nodes;
#pragma omp parallel for num_threads(threads_) schedule(static) if (ndof > 30000)
  for (std::size_t i = 0; i < ndof; ++i) x_[i] = model_.X[i] + u[i];
  const double* x = x_.data();
  for (std::size_t pi = 0; pi < pairs_.size(); ++pi) {
    const ContactPair& p = pairs_[pi];
    const double band = settings_.search_factor * p.master_edge;
    auto add = [&](std::size_t k, std::int32_t tri, const double* N, const V3& n, double h) {
      state_.pair.push_back(static_cast<std::int32_t>(pi));
      state_.slave.push_back(p.slave_nodes[k]);
      state_.slave_index.push_back(static_cast<std::int32_t>(k));
      state_.triangle.push_back(tri);
      for (int d = 0; d < 3; ++d) state_.weights.push_back(N[d]), state_.normal.push_back(n[d]);
      state_.gap.push_back(h);
      state_.area.push_back(p.slave_area[k]);
    };
    if (p.rigid_plane) {
      const double N0[3] = {0, 0, 0};
      for (std::size_t k = 0; k < p.slave_nodes.size(); ++k) {
        const std::int32_t s = p.slave_nodes[k];
        const double h = dot(sub(x + 3 * s, p.plane_point.data()), p.plane_normal);
        if (h <= band) add(k, -1, N0, p.plane_normal, h);
      }
      continue;
    }
    build_grid(p, x, band);
    const Grid& g = grid_;
    const std::size_t S = p.slave_nodes.size();
    slot_triangle_.assign(S, -1);
    slot_data_.resize(7 * S);
    std::int32_t* slot_t = slot_triangle_.data();
    double* slot = slot_data_.data();
    // Narrow phase per slave node (independent: parallel); candidates are gathered in slave order.
#pragma omp parallel for num_threads(threads_) schedule(static) if (S > 2000)
    for (std::size_t k = 0; k < S; ++k) {
      const std::int32_t s = p.slave_nodes[k];
      const double* xs = x + 3 * s;
      int cidx[3];
      bool inside = true;
      for (int c = 0; c < 3; ++c) {
        const double f = (xs[c] - g.lo[c]) / g.cell;
        inside = inside && f >= 0 && f < g.n[c];
        cidx[c] = static_cast<int>(f);
      }
      if (!inside) continue;
      const std::size_t cell = (static_cast<std::size_t>(cidx[2]) * g.n[1] + cidx[1]) * g.n[0] + cidx[0];
      double best_abs = std::numeric_limits<double>::infinity();
      double* out = slot + 7 * k;
      for (std::int32_t it = g.count[cell]; it < g.start[cell]; ++it) {
        const std::int32_t t = g.items[static_cast<std::size_t>(it)];
        const std::int32_t* tri = &p.master_triangles[3 * static_cast<std::size_t>(t)];
        if (tri[0] == s || tri[1] == s || tri[2] == s) continue;
        const double* tn = &g.normal[4 * static_cast<std::size_t>(t)];
        if (tn[3] == 0) continue;  // degenerate triangle
        const V3 n{tn[0], tn[1], tn[2]};
        const double *a = x + 3 * tri[0], *b = x + 3 * tri[1], *c = x + 3 * tri[2];
        const double h = dot(sub(xs, a), n);
        if (h > band || h < -band || std::abs(h) >= best_abs) continue;
        // Barycentric coordinates of the projection x_s - h n (signed sub-areas over the area).
        const V3 pb = sub(xs, b), pc = sub(xs, c);
        const double la = dot(cross(sub(c, b), pb), n) * tn[3];
        const double lb = dot(cross(sub(a, c), pc), n) * tn[3];
        const double lc = 1.0 - la - lb;
        constexpr double eps = 1e-3;  // closes the seams between neighbouring triangles
        if (la < -eps || lb < -eps || lc < -eps) continue;
        best_abs = std::abs(h);
        slot_t[k] = t;
        const double ca = std::max(la, 0.0), cb = std::max(lb, 0.0), cc = std::max(lc, 0.0), sum = ca + cb + cc;
        out[0] = ca / sum, out[1] = cb / sum, out[2] = cc / sum;
        out[3] = n[0], out[4] = n[1], out[5] = n[2], out[6] = h;
      }
    }
    for (std::size_t k = 0; k < S; ++k)
      if (slot_t[k] >= 0) {
        const double* d = slot + 7 * k;
        add(k, slot_t[k], d, {d[3], d[4], d[5]}, d[6]);
      }
  }
  const std::size_t K = state_.size();
  state_.reaction.assign(3 * K, 0.0);
  state_.compliance.assign(K, 0.0);
  state_.status.assign(K, ContactStatus::open);
}

void ContactSolver::check_initial_overlap(const double* u) const {
  ContactSolver probe(model_);
  probe.settings_.search_factor = std::max(settings_.search_factor, 2.0);
  probe.detect(u);
  const ContactState& st = probe.state_;
  std::size_t worst = st.size();
  double worst_h = 0;
  for (std::size_t k = 0; k < st.size(); ++k) {
    const double tol = 1e-3 * std::max(pairs_[static_cast<std::size_t>(st.pair[k])].master_edge, 1e-12);
    if (st.gap[k] < -tol && st.gap[k] < worst_h) worst = k, worst_h = st.gap[k];
  }
  if (worst == st.size()) return;
  const ContactPair& p = pairs_[static_cast<std::size_t>(st.pair[worst])];
  std::size_t input_node = model_.input_node(static_cast<std::size_t>(st.slave[worst]));
  std::string body;
  for (const auto& b : model_.bodies)
    if (input_node >= b.node_begin && input_node < b.node_end) body = b.name, input_node -= b.node_begin;
  std::ostringstream found, expected;
  found << "node " << input_node + 1 << " of body '" << body << "' is " << -worst_h * 1e3 << " mm inside the master surface";
  expected << "bodies apart or touching at t = 0 (overlap < " << 1e-3 * p.master_edge * 1e3
           << " mm); move them apart with bodies.translate";
  throw InputError("scenario", p.name, expected.str(), found.str());
}

ContactStepReport ContactSolver::solve(const double* u, double* v, const double* v_old, const double* inv_mass,
                                       double velocity_per_force, double dt, double dt_prev) {
  ContactStepReport rep;
  if (pairs_.empty()) return rep;
  detect(u);
  const std::size_t K = state_.size();
  rep.candidates = K;
  if (K == 0) return rep;
  const double c = velocity_per_force;

  // Nodes and weights of one candidate: slave with +1, master nodes with -N_i.
  auto nodes_of = [&](std::size_t k, std::int32_t node[4], double wt[4]) -> int {
    node[0] = state_.slave[k], wt[0] = 1.0;
    const std::int32_t t = state_.triangle[k];
    if (t < 0) return 1;
    const std::int32_t* tri = pairs_[static_cast<std::size_t>(state_.pair[k])].master_triangles.data() + 3 * t;
    for (int i = 0; i < 3; ++i) node[1 + i] = tri[i], wt[1 + i] = -state_.weights[3 * k + i];
    return 4;
  };
  auto relative_velocity = [&](const double* vel, int m, const std::int32_t* node, const double* wt) {
    V3 r{0, 0, 0};
    for (int a = 0; a < m; ++a)
      for (int d = 0; d < 3; ++d) r[d] += wt[a] * vel[3 * node[a] + d];
    return r;
  };

  // Compliances: w = c (n.D_s n + sum N_i^2 n.D_i n), D the inverse masses (0 on prescribed dofs).
  for (std::size_t k = 0; k < K; ++k) {
    std::int32_t node[4];
    double wt[4];
    const int m = nodes_of(k, node, wt);
    const double* n = &state_.normal[3 * k];
    double w = 0;
    for (int a = 0; a < m; ++a)
      for (int d = 0; d < 3; ++d) w += wt[a] * wt[a] * n[d] * n[d] * inv_mass[3 * node[a] + d];
    state_.compliance[k] = c * w;
  }

  // Warm start: the previous step's reaction of the same slave node, projected on the new cone.
  for (std::size_t k = 0; k < K; ++k) {
    const std::size_t pi = static_cast<std::size_t>(state_.pair[k]);
    const double* last = &last_reaction_[pi][3 * static_cast<std::size_t>(state_.slave_index[k])];
    if (last[0] == 0 && last[1] == 0 && last[2] == 0) continue;
    const V3 n{state_.normal[3 * k], state_.normal[3 * k + 1], state_.normal[3 * k + 2]};
    const V3 r0 = coulomb_cone_projection({last[0], last[1], last[2]}, n, pairs_[pi].friction);
    std::int32_t node[4];
    double wt[4];
    const int m = nodes_of(k, node, wt);
    for (int d = 0; d < 3; ++d) state_.reaction[3 * k + d] = r0[d];
    for (int a = 0; a < m; ++a)
      for (int d = 0; d < 3; ++d) v[3 * node[a] + d] += c * wt[a] * r0[d] * inv_mass[3 * node[a] + d];
  }
  for (auto& last : last_reaction_) std::fill(last.begin(), last.end(), 0.0);  // (sized by the surfaces, not per step)

  // Uzawa iterations, Gauss-Seidel over the candidates (eqs. 11-12 with rho = 1/w: one
  // iteration is exact for an isolated frictionless node).
  const double inv_dt = dt > 0 ? 1.0 / dt : 0.0;
  double residual = 0;
  int it = 0;
  for (it = 1; it <= settings_.max_iterations; ++it) {
    double max_dr = 0, max_r = 0;
    for (std::size_t k = 0; k < K; ++k) {
      const double w = state_.compliance[k];
      if (!(w > 0)) continue;
      std::int32_t node[4];
      double wt[4];
      const int m = nodes_of(k, node, wt);
      const V3 n{state_.normal[3 * k], state_.normal[3 * k + 1], state_.normal[3 * k + 2]};
      const double mu = pairs_[static_cast<std::size_t>(state_.pair[k])].friction;
      const V3 uu = relative_velocity(v, m, node, wt);
      const double un_vel = dot(uu, n);
      const V3 ut{uu[0] - un_vel * n[0], uu[1] - un_vel * n[1], uu[2] - un_vel * n[2]};
      const double un = un_vel + state_.gap[k] * inv_dt;  // the gap folded in: no penetration after the step
      double* r = &state_.reaction[3 * k];
      const V3 rk{r[0], r[1], r[2]};
      const V3 next = coulomb_cone_projection(augmented_traction(rk, ut, un, n, mu, 1.0 / w), n, mu);
      const V3 dr{next[0] - rk[0], next[1] - rk[1], next[2] - rk[2]};
      const double drn = norm(dr);
      max_dr = std::max(max_dr, drn);
      max_r = std::max(max_r, norm(next));
      if (drn == 0) continue;
      for (int d = 0; d < 3; ++d) r[d] = next[d];
      for (int a = 0; a < m; ++a)
        for (int d = 0; d < 3; ++d) v[3 * node[a] + d] += c * wt[a] * dr[d] * inv_mass[3 * node[a] + d];
    }
    residual = max_r > 0 ? max_dr / max_r : 0.0;
    if (residual <= settings_.tolerance) break;
  }
  rep.iterations = std::min(it, settings_.max_iterations);
  for (std::size_t k = 0; k < K; ++k) {
    double* last = &last_reaction_[static_cast<std::size_t>(state_.pair[k])][3 * static_cast<std::size_t>(state_.slave_index[k])];
    for (int d = 0; d < 3; ++d) last[d] = state_.reaction[3 * k + d];
  }
  rep.residual = residual;
  rep.converged = residual <= settings_.tolerance;

  // Status, resultants and the work of the reactions (trapezoid halves over du^{n-1/2}, du^{n+1/2}).
  double max_rn = 0;
  for (std::size_t k = 0; k < K; ++k) max_rn = std::max(max_rn, dot({state_.reaction[3 * k], state_.reaction[3 * k + 1], state_.reaction[3 * k + 2]},
                                                                    {state_.normal[3 * k], state_.normal[3 * k + 1], state_.normal[3 * k + 2]}));
  for (std::size_t k = 0; k < K; ++k) {
    const V3 r{state_.reaction[3 * k], state_.reaction[3 * k + 1], state_.reaction[3 * k + 2]};
    const V3 n{state_.normal[3 * k], state_.normal[3 * k + 1], state_.normal[3 * k + 2]};
    const double rn = dot(r, n);
    if (!(rn > 1e-12 * max_rn) || max_rn == 0) {
      state_.status[k] = ContactStatus::open;
      continue;
    }
    const V3 rt{r[0] - rn * n[0], r[1] - rn * n[1], r[2] - rn * n[2]};
    const double mu = pairs_[static_cast<std::size_t>(state_.pair[k])].friction;
    state_.status[k] = norm(rt) < mu * rn * (1 - 1e-6) ? ContactStatus::stick : ContactStatus::slip;
    ++rep.active;
    (state_.status[k] == ContactStatus::stick ? rep.sticking : rep.slipping)++;
    for (int d = 0; d < 3; ++d) rep.force[d] += r[d];
    rep.normal_force += rn;
    rep.area += state_.area[k];
    const double pressure = rn / state_.area[k];
    if (pressure > rep.peak_pressure) rep.peak_pressure = pressure, rep.peak_node = state_.slave[k];
    std::int32_t node[4];
    double wt[4];
    const int m = nodes_of(k, node, wt);
    const V3 u_new = relative_velocity(v, m, node, wt), u_old = relative_velocity(v_old, m, node, wt);
    const double un_new = dot(u_new, n), un_old = dot(u_old, n);
    rep.normal_work_forward += dt * rn * un_new;
    rep.normal_work_back += dt_prev * rn * un_old;
    rep.friction_work_forward += dt * (dot(r, u_new) - rn * un_new);
    rep.friction_work_back += dt_prev * (dot(r, u_old) - rn * un_old);
    for (int a = 0; a < m; ++a)
      for (int d = 0; d < 3; ++d) {
        const std::size_t dof = 3 * static_cast<std::size_t>(node[a]) + d;
        if (inv_mass[dof] != 0) continue;  // a prescribed dof: its support takes this share
        const double support = -wt[a] * r[d];
        rep.support_work_forward += dt * support * v[dof];
        rep.support_work_back += dt_prev * support * v_old[dof];
      }
  }
  return rep;
}

void ContactSolver::node_fields(std::vector<double>& pressure, std::vector<double>& traction, std::vector<double>& status,
                                std::vector<double>& gap) const {
  const std::size_t N = model_.num_nodes;
  pressure.assign(N, 0.0);
  traction.assign(3 * N, 0.0);
  status.assign(N, -1.0);
  gap.assign(N, std::numeric_limits<double>::quiet_NaN());
  for (std::size_t k = 0; k < state_.size(); ++k) {
    const std::size_t s = static_cast<std::size_t>(state_.slave[k]);
    const double* r = &state_.reaction[3 * k];
    const double* n = &state_.normal[3 * k];
    const double rn = r[0] * n[0] + r[1] * n[1] + r[2] * n[2];
    pressure[s] += rn / state_.area[k];
    for (int d = 0; d < 3; ++d) traction[3 * s + d] += (r[d] - rn * n[d]) / state_.area[k];
    status[s] = std::max(status[s], static_cast<double>(state_.status[k]));
    if (std::isnan(gap[s]) || state_.gap[k] < gap[s]) gap[s] = state_.gap[k];
  }
}

}  // namespace tactus::solver
