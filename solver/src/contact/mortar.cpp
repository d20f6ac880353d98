// Mortar (segment-to-segment) master: contact constraints as integrals over the slave surface
// (Puso & Laursen 2004; Popp, Gee & Wall 2009), in the row form of the contact seam (contact.hpp).
//
// Each step, every slave triangle is projected onto the plane of each master triangle near it,
// clipped against it (Sutherland-Hodgman: the mortar segment), and the segment is integrated
// exactly (edge-midpoint rule on a fan of sub-triangles: the integrands are quadratic). For slave
// node j with shape function lambda_j:
//   D_j = int lambda_j dA,   M_jk = int lambda_j mu_k dA,   g_j = int lambda_j g dA,
// over the segments, mu_k the master shape functions and g = (x_s - x_m) . n the gap along the
// master's outward normal. Row j is then: the slave node with weight 1, master node k with
// -M_jk / D_j, the gap g_j / D_j, the normal int lambda_j n dA normalised, and the area D_j, so the
// reported pressure r_n / D_j is a surface density over the area actually in contact.
//
// Why lumped D with standard (not dual) multiplier functions: every weight stays positive, the row
// of node j is local (no coupling through D), and sum_k M_jk = D_j exactly, so a rigid motion of
// both sides gives no relative velocity; the bi-potential solver and its per-node cone projection
// (paper eqs. 11-12) are used unchanged. With segment-based integration a uniform pressure is
// transmitted exactly across non-matching meshes (the contact patch test).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "detection.hpp"
#include "tactus/solver/contact.hpp"

namespace tactus::solver {

namespace {

struct P2 {
  double u, v;
};
double cross2(const P2& o, const P2& a, const P2& b) { return (a.u - o.u) * (b.v - o.v) - (a.v - o.v) * (b.u - o.u); }

// Sutherland-Hodgman: `poly` (n vertices, any orientation) clipped by the counter-clockwise
// triangle `tri`. Returns the vertex count of the result in `out` (at most 9).
int clip_by_triangle(const P2* poly, int n, const std::array<P2, 3>& tri, std::array<P2, 12>& out) {
  std::array<P2, 12> a, b;
  std::copy(poly, poly + n, a.begin());
  int m = n;
  for (int e = 0; e < 3 && m > 0; ++e) {
    const P2 &p0 = tri[static_cast<std::size_t>(e)], &p1 = tri[static_cast<std::size_t>((e + 1) % 3)];
    int k = 0;
    for (int i = 0; i < m; ++i) {
      const P2 &s = a[static_cast<std::size_t>(i)], &t = a[static_cast<std::size_t>((i + 1) % m)];
      const double ds = cross2(p0, p1, s), dt = cross2(p0, p1, t);
      if (ds >= 0) b[static_cast<std::size_t>(k++)] = s;
      if ((ds >= 0) != (dt >= 0)) {
        const double w = ds / (ds - dt);
        b[static_cast<std::size_t>(k++)] = {s.u + w * (t.u - s.u), s.v + w * (t.v - s.v)};
      }
    }
    m = k;
    a = b;
  }
  out = a;
  return m;
}

// Barycentric coordinates of p in triangle t (signed: any orientation).
std::array<double, 3> barycentric(const P2& p, const std::array<P2, 3>& t) {
  const double total = cross2(t[0], t[1], t[2]);
  const double l1 = cross2(t[0], p, t[2]) / total, l2 = cross2(t[0], t[1], p) / total;
  return {1.0 - l1 - l2, l1, l2};
}

// What the segments of one step give each slave node.
struct NodeIntegrals {
  double D = 0, G = 0;
  Vec3 N{0, 0, 0};
  std::vector<std::pair<std::int32_t, double>> M;  // master node, int lambda_j mu_k
  void add_master(std::int32_t node, double value) {
    for (auto& [n, v] : M)
      if (n == node) {
        v += value;
        return;
      }
    M.emplace_back(node, value);
  }
};

class MortarSurface final : public ContactMaster {
 public:
  explicit MortarSurface(std::vector<std::int32_t> triangles) : triangles_(std::move(triangles)) {}
  std::string describe() const override { return "mortar surface (" + std::to_string(triangles_.size() / 3) + " triangles)"; }
  const std::vector<std::int32_t>& triangles() const override { return triangles_; }
  void detect(const ContactPair& p, std::int32_t pi, const double* x, double band, DetectionScratch& scratch, ContactRows& rows,
              int threads) const override;

 private:
  std::vector<std::int32_t> triangles_;  // 3 per triangle, outward
  // Per-step storage, reused (detect is called by one thread per pair and step).
  mutable std::vector<NodeIntegrals> integrals_;
  mutable std::vector<std::size_t> seen_;
  mutable std::vector<std::int32_t> masters_;
  mutable std::vector<double> weights_;
};

void MortarSurface::detect(const ContactPair& p, std::int32_t pi, const double* x, double band, DetectionScratch& scratch, ContactRows& rows,
                           int /*threads*/) const {
  DetectionScratch::Grid& g = scratch.grid;
  build_triangle_grid(triangles_, p.search_scale, x, band, g);
  const std::size_t S = p.slave_nodes.size(), T = triangles_.size() / 3;
  std::vector<NodeIntegrals>& node = integrals_;  // kept between steps: no allocation once grown
  node.resize(S);
  for (auto& ni : node) ni.D = 0, ni.G = 0, ni.N = {0, 0, 0}, ni.M.clear();
  std::vector<std::size_t>& seen = seen_;
  seen.assign(T, std::numeric_limits<std::size_t>::max());
  auto slave_index = [&](std::int32_t v) {
    return static_cast<std::size_t>(std::lower_bound(p.slave_nodes.begin(), p.slave_nodes.end(), v) - p.slave_nodes.begin());
  };
  for (std::size_t st = 0; st * 3 < p.slave_triangles.size(); ++st) {
    const std::int32_t* sv = &p.slave_triangles[3 * st];
    const double* xs[3] = {x + 3 * sv[0], x + 3 * sv[1], x + 3 * sv[2]};
    const Vec3 ns = cross(sub(xs[1], xs[0]), sub(xs[2], xs[0]));
    const double slave_area = 0.5 * norm(ns);
    if (!(slave_area > 0)) continue;
    std::size_t jn[3];
    for (int i = 0; i < 3; ++i) jn[i] = slave_index(sv[i]);
    int lo[3], hi[3];
    for (int c = 0; c < 3; ++c) {
      const double a = std::min({xs[0][c], xs[1][c], xs[2][c]}), b = std::max({xs[0][c], xs[1][c], xs[2][c]});
      if (b < g.lo[c] || a > g.lo[c] + g.cell * g.n[c])
        lo[c] = 1, hi[c] = 0;  // outside the grid
      else
        lo[c] = g.cell_of(a, c), hi[c] = g.cell_of(b, c);
    }
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i) {
          const std::size_t cell =
              (static_cast<std::size_t>(k) * static_cast<std::size_t>(g.n[1]) + static_cast<std::size_t>(j)) * static_cast<std::size_t>(g.n[0]) +
              static_cast<std::size_t>(i);
          for (std::int32_t it = g.count[cell]; it < g.start[cell]; ++it) {
            const auto t = static_cast<std::size_t>(g.items[static_cast<std::size_t>(it)]);
            if (seen[t] == st) continue;
            seen[t] = st;
            const std::int32_t* mv = &triangles_[3 * t];
            if (mv[0] == sv[0] || mv[0] == sv[1] || mv[0] == sv[2] || mv[1] == sv[0] || mv[1] == sv[1] || mv[1] == sv[2] || mv[2] == sv[0] ||
                mv[2] == sv[1] || mv[2] == sv[2])
              continue;  // a neighbour on the same surface
            const double* tn = &g.normal[4 * t];
            if (tn[3] == 0) continue;
            const Vec3 n{tn[0], tn[1], tn[2]};
            // The surfaces must face each other (both outward): a slave triangle pairs only with
            // master faces within 60 degrees of opposite, not with the side faces at an edge.
            if (dot(ns, n) > -0.5 * 2 * slave_area) continue;
            const double* m0 = x + 3 * mv[0];
            double h[3];
            for (int a = 0; a < 3; ++a) h[a] = dot(sub(xs[a], m0), n);
            if (std::min({h[0], h[1], h[2]}) > band || std::max({h[0], h[1], h[2]}) < -band) continue;
            // The master plane's frame: e1 along the first edge, e2 = n x e1 (counter-clockwise about n).
            const Vec3 e1r = sub(x + 3 * mv[1], m0);
            const double l1 = norm(e1r);
            const Vec3 e1{e1r[0] / l1, e1r[1] / l1, e1r[2] / l1}, e2 = cross(n, e1);
            auto to2 = [&](const double* q) {
              const Vec3 d = sub(q, m0);
              return P2{dot(d, e1), dot(d, e2)};
            };
            const std::array<P2, 3> mt{P2{0, 0}, to2(x + 3 * mv[1]), to2(x + 3 * mv[2])};
            const std::array<P2, 3> sq{to2(xs[0]), to2(xs[1]), to2(xs[2])};
            const double projected = 0.5 * std::abs(cross2(sq[0], sq[1], sq[2]));
            if (!(projected > 1e-12 * slave_area)) continue;
            std::array<P2, 12> poly;
            const int nv = clip_by_triangle(sq.data(), 3, mt, poly);
            if (nv < 3) continue;
            const double to_slave = slave_area / projected;  // dA on the slave per dA in the plane
            for (int f = 1; f + 1 < nv; ++f) {
              const P2 &a = poly[0], &b = poly[static_cast<std::size_t>(f)], &c = poly[static_cast<std::size_t>(f + 1)];
              const double area = 0.5 * std::abs(cross2(a, b, c));
              if (!(area > 0)) continue;
              const P2 qp[3] = {
                  {0.5 * (a.u + b.u), 0.5 * (a.v + b.v)}, {0.5 * (b.u + c.u), 0.5 * (b.v + c.v)}, {0.5 * (c.u + a.u), 0.5 * (c.v + a.v)}};
              for (const P2& q : qp) {
                const auto lam = barycentric(q, sq), mu = barycentric(q, mt);
                const double dA = area / 3.0 * to_slave;
                const double gap = lam[0] * h[0] + lam[1] * h[1] + lam[2] * h[2];  // (x_s(q) - x_m(q)) . n
                for (int s = 0; s < 3; ++s) {
                  NodeIntegrals& ni = node[jn[s]];
                  const double w = lam[static_cast<std::size_t>(s)] * dA;
                  ni.D += w, ni.G += w * gap;
                  for (int d = 0; d < 3; ++d) ni.N[d] += w * n[d];
                  for (int k2 = 0; k2 < 3; ++k2) ni.add_master(mv[k2], w * mu[static_cast<std::size_t>(k2)]);
                }
              }
            }
          }
        }
  }
  std::vector<std::int32_t>& masters = masters_;
  std::vector<double>& weights = weights_;
  for (std::size_t k = 0; k < S; ++k) {
    const NodeIntegrals& ni = node[k];
    const double nn = norm(ni.N);
    if (!(ni.D > 0) || !(nn > 0)) continue;
    masters.clear(), weights.clear();
    for (const auto& [m, v] : ni.M) masters.push_back(m), weights.push_back(-v / ni.D);
    rows.add(pi, static_cast<std::int32_t>(k), p.slave_nodes[k], masters.data(), weights.data(), static_cast<int>(masters.size()),
             {ni.N[0] / nn, ni.N[1] / nn, ni.N[2] / nn}, ni.G / ni.D, ni.D);
  }
}

}  // namespace

std::shared_ptr<const ContactMaster> mortar_surface_master(std::vector<std::int32_t> triangles) {
  return std::make_shared<MortarSurface>(std::move(triangles));
}

}  // namespace tactus::solver
