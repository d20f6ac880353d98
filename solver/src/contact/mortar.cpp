// Mortar (segment-to-segment) master: contact constraints as integrals over the slave surface
// (Puso & Laursen 2004; Popp, Gee & Wall 2009), in the row form of the contact seam (contact.hpp).
//
// Each step, every slave triangle is projected onto the plane of each master triangle near it,
// clipped against it (Sutherland-Hodgman: the mortar segment), and the segment is integrated
// exactly (edge-midpoint rule on a fan of sub-triangles: the integrands are quadratic). For slave
// node j with shape function lambda_j and dual multiplier function psi_j:
//   D_j = int lambda_j dA,   M_jk = int psi_j mu_k dA,   g_j = int psi_j g dA,
// over the segments, mu_k the master shape functions and g = (x_s - x_m) . n the gap along the
// master's outward normal. Row j is then: the slave node with weight 1, master node k with
// -M_jk / D_j, the gap g_j / D_j, the normal int lambda_j n dA normalised, and the area D_j, so the
// reported pressure r_n / D_j is a surface density over the area actually in contact.
//
// Why dual multipliers (Wohlmuth 2000; for explicit dynamics Cichosz & Bischoff 2011): psi_j is
// biorthogonal to the slave shape functions (int psi_j lambda_i = delta_ij D_j), so the weighted
// gap's rate is exactly D_j times the row's relative velocity v_j - sum_k (M_jk / D_j) v_k. Each
// row stays local (one slave node) and the bi-potential solver with its per-node cone projection
// (paper eqs. 11-12) is used unchanged. With standard multipliers and a lumped D the gap moves with
// the neighbours' velocities that the row does not see: on the hand-block case that fed energy in
// at every touch until the run blew up. psi_j is built per slave triangle on its covered part
// (Popp, Gee & Wall 2012), so D_j stays the positive covered tributary area at the contact's
// border; sum_k M_jk = D_j, so a rigid motion of both sides gives no relative velocity. With
// segment-based integration a uniform pressure is transmitted exactly across non-matching meshes
// (the contact patch test).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <omp.h>

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
  std::vector<std::pair<std::int32_t, double>> M;  // master node, int psi_j mu_k
  void add_master(std::int32_t node, double value) {
    for (auto& [n, v] : M)
      if (n == node) {
        v += value;
        return;
      }
    M.emplace_back(node, value);
  }
};

// One quadrature point of a mortar segment: the slave and master shape functions there, its
// slave-surface weight, the gap and the master normal.
struct QuadraturePoint {
  std::array<double, 3> lambda, mu;
  double dA, gap;
  Vec3 n;
  std::array<std::int32_t, 3> master;
};

// A slave vertex counts as over a master triangle up to this far beyond its edges (barycentric,
// i.e. a fraction of the triangle's height; the node-to-surface search reaches as far beyond an
// open edge): a slave node on the master's boundary edge stays held when round-off or the
// deformation moves it just outside.
constexpr double kOverMasterReach = 0.05;

// Where a slave triangle's points change from one master face to a nearer one, its fan
// sub-triangles are split in four down to this many levels (1/32 of their size) to follow the
// boundary; the error left is in the strip of the last level along it.
constexpr int kNearerSplits = 5;

// The dual basis of one slave triangle on the part of it that is covered (Popp, Gee & Wall 2012):
// psi_j = sum_k a_jk lambda_k with a = D_e M_e^-1, D_e = diag(int lambda_j), M_e = int lambda_j
// lambda_k over the covered part, so that int psi_j lambda_k = delta_jk int lambda_j there. Returns
// false when M_e is too close to singular (a sliver of coverage), where the standard basis is used.
bool covered_dual_basis(const std::vector<QuadraturePoint>& points, std::array<std::array<double, 3>, 3>& a) {
  double M[3][3] = {}, D[3] = {};
  for (const QuadraturePoint& q : points)
    for (int j = 0; j < 3; ++j) {
      D[j] += q.lambda[static_cast<std::size_t>(j)] * q.dA;
      for (int k = 0; k < 3; ++k) M[j][k] += q.lambda[static_cast<std::size_t>(j)] * q.lambda[static_cast<std::size_t>(k)] * q.dA;
    }
  const double c00 = M[1][1] * M[2][2] - M[1][2] * M[2][1], c01 = M[1][2] * M[2][0] - M[1][0] * M[2][2], c02 = M[1][0] * M[2][1] - M[1][1] * M[2][0];
  const double det = M[0][0] * c00 + M[0][1] * c01 + M[0][2] * c02;
  // Full coverage gives det / (M00 M11 M22) = 16/27 (M = A/12 (1 + delta)); below 1 % of that the
  // inverse amplifies the quadrature's round-off more than the dual basis gains.
  if (!(det > 0.01 * (16.0 / 27.0) * M[0][0] * M[1][1] * M[2][2])) return false;
  const double inv[3][3] = {{c00 / det, (M[0][2] * M[2][1] - M[0][1] * M[2][2]) / det, (M[0][1] * M[1][2] - M[0][2] * M[1][1]) / det},
                            {c01 / det, (M[0][0] * M[2][2] - M[0][2] * M[2][0]) / det, (M[0][2] * M[1][0] - M[0][0] * M[1][2]) / det},
                            {c02 / det, (M[0][1] * M[2][0] - M[0][0] * M[2][1]) / det, (M[0][0] * M[1][1] - M[0][1] * M[1][0]) / det}};
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k < 3; ++k) a[static_cast<std::size_t>(j)][static_cast<std::size_t>(k)] = D[j] * inv[j][k];
  return true;
}

// One slave triangle's share of its three nodes' integrals (filled in parallel, added in order).
struct TriangleIntegrals {
  std::array<std::size_t, 3> node;  // positions in the pair's slave_nodes
  std::array<double, 3> D, G;
  std::array<Vec3, 3> N;
  std::array<bool, 3> over;  // the vertex itself lies over a master triangle
  std::size_t terms_begin, terms_end;
};
struct MasterTerm {
  int vertex;  // 0..2 of the slave triangle
  std::int32_t master;
  double value;  // int psi_j mu_k over the segments
};

// One slave triangle's segments: D_j = int lambda_j, G_j = int psi_j g, M_jk = int psi_j mu_k,
// N_j = int lambda_j n. With the dual basis D_j v_j - sum_k M_jk v_k is the rate of G_j (the row's
// velocity is the weighted gap's rate) and sum_k M_jk = D_j (a rigid motion of both sides is no
// relative motion). The points come in runs of one master triangle each: M is summed per run.
void integrate_segments(const std::vector<QuadraturePoint>& points, TriangleIntegrals& out, std::vector<MasterTerm>& terms) {
  std::array<std::array<double, 3>, 3> a{};
  if (!covered_dual_basis(points, a)) a = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  out.D = {0, 0, 0}, out.G = {0, 0, 0}, out.N = {Vec3{0, 0, 0}, Vec3{0, 0, 0}, Vec3{0, 0, 0}};
  out.terms_begin = terms.size();
  double block[3][3] = {};
  for (std::size_t i = 0; i < points.size(); ++i) {
    const QuadraturePoint& q = points[i];
    for (std::size_t s = 0; s < 3; ++s) {
      const double l = q.lambda[s] * q.dA, psi = (a[s][0] * q.lambda[0] + a[s][1] * q.lambda[1] + a[s][2] * q.lambda[2]) * q.dA;
      out.D[s] += l, out.G[s] += psi * q.gap;
      for (std::size_t d = 0; d < 3; ++d) out.N[s][d] += l * q.n[d];
      for (std::size_t k = 0; k < 3; ++k) block[s][k] += psi * q.mu[k];
    }
    if (i + 1 == points.size() || points[i + 1].master != q.master) {  // the end of this master triangle's run
      for (int s = 0; s < 3; ++s)
        for (int k = 0; k < 3; ++k) {
          terms.push_back({s, q.master[static_cast<std::size_t>(k)], block[s][k]});
          block[s][k] = 0;
        }
    }
  }
  out.terms_end = terms.size();
}

// A master triangle one slave triangle is clipped against: the frame of its plane (origin m0,
// outward normal n, e1 along its first edge, e2 = n x e1), itself and the slave triangle in that
// frame, and the slave vertices' heights over the plane.
struct Candidate {
  std::size_t t;
  const double* m0;
  Vec3 n, e1, e2;
  std::array<P2, 3> mt, sq;
  std::array<double, 3> h;
};

// What one chunk of slave triangles gives, reused from step to step.
struct SegmentChunk {
  std::vector<Candidate> candidates;
  std::vector<QuadraturePoint> points;
  std::vector<TriangleIntegrals> triangles;
  std::vector<MasterTerm> terms;
};
constexpr std::size_t kChunks = 64;

// The segments are integrated again when a node of the pair has moved this far (in master edge
// lengths) since they last were; in between each row's gap follows its own kinematics,
// h = h_0 + n . ((x_j - x_j0) - sum_k w_k (x_k - x_k0)), which is what the row's velocity
// constraint integrates (exact for the dual rows while the weights hold). 2 % of an element moves a
// weight by about 2 %, far below the discretisation's own error; a contact can not start unseen in
// between, as the band reaches 50 %.
constexpr double kMortarRefresh = 0.02;

class MortarSurface final : public ContactMaster {
 public:
  explicit MortarSurface(std::vector<std::int32_t> triangles) : triangles_(std::move(triangles)) {}
  std::string describe() const override { return "mortar surface (" + std::to_string(triangles_.size() / 3) + " triangles)"; }
  const std::vector<std::int32_t>& triangles() const override { return triangles_; }
  void detect(const ContactPair& p, std::int32_t pi, const double* x, double band, DetectionScratch& scratch, ContactRows& rows,
              int threads) const override;

 private:
  std::vector<std::int32_t> triangles_;  // 3 per triangle, outward
  // Storage of one integration, reused (detect is called by one thread per pair and step); what
  // lasts from one step to the next is the pair's (DetectionScratch::mortar).
  mutable std::vector<NodeIntegrals> integrals_;
  mutable std::vector<SegmentChunk> chunks_;
  mutable std::vector<std::vector<std::size_t>> seen_;  // per thread and master triangle: the last slave triangle that tried it
  mutable std::vector<char> over_;                      // per slave node: its own position is over a master triangle
  void segments_of(const ContactPair& p, const std::vector<std::size_t>& slave_local, std::size_t st, const double* x, double band,
                   const DetectionScratch::Grid& g, std::vector<std::size_t>& seen, SegmentChunk& w) const;
};

// A slave triangle at x: its vertices, normal (twice the area long) and area.
struct SlaveTriangle {
  const std::int32_t* v;
  const double* xs[3];
  Vec3 ns;
  double area;
};

// Master triangle t (triangles: 3 node ids each) as a candidate of slave triangle s, when it lies
// within the band (sb: the slave's box), faces it, and its projection can overlap the slave's.
bool master_candidate(const SlaveTriangle& s, const double sb[6], std::size_t t, const std::vector<std::int32_t>& triangles, const double* x,
                      double band, const DetectionScratch::Grid& g, Candidate& out) {
  const double* mb = &g.extent[6 * t];  // most candidates of a cell are beyond the band: their boxes tell
  if (mb[0] > sb[3] + band || mb[3] < sb[0] - band || mb[1] > sb[4] + band || mb[4] < sb[1] - band || mb[2] > sb[5] + band || mb[5] < sb[2] - band)
    return false;
  const std::int32_t* mv = &triangles[3 * t];
  const std::int32_t* sv = s.v;
  if (mv[0] == sv[0] || mv[0] == sv[1] || mv[0] == sv[2] || mv[1] == sv[0] || mv[1] == sv[1] || mv[1] == sv[2] || mv[2] == sv[0] || mv[2] == sv[1] ||
      mv[2] == sv[2])
    return false;  // a neighbour on the same surface
  const double* tn = &g.normal[4 * t];
  if (tn[3] == 0) return false;
  const Vec3 n{tn[0], tn[1], tn[2]};
  // The surfaces must face each other (both outward): a slave triangle pairs only with
  // master faces within 60 degrees of opposite, not with the side faces at an edge.
  if (dot(s.ns, n) > -0.5 * 2 * s.area) return false;
  const double* m0 = x + 3 * mv[0];
  double h[3];
  for (int a = 0; a < 3; ++a) h[a] = dot(sub(s.xs[a], m0), n);
  if (std::min({h[0], h[1], h[2]}) > band || std::max({h[0], h[1], h[2]}) < -band) return false;
  // The master plane's frame: e1 along the first edge, e2 = n x e1 (counter-clockwise about n).
  const Vec3 e1r = sub(x + 3 * mv[1], m0);
  const double l1 = norm(e1r);
  const Vec3 e1{e1r[0] / l1, e1r[1] / l1, e1r[2] / l1}, e2 = cross(n, e1);
  auto to2 = [&](const double* q) {
    const Vec3 d = sub(q, m0);
    return P2{dot(d, e1), dot(d, e2)};
  };
  const std::array<P2, 3> mt{P2{0, 0}, to2(x + 3 * mv[1]), to2(x + 3 * mv[2])};
  const std::array<P2, 3> sq{to2(s.xs[0]), to2(s.xs[1]), to2(s.xs[2])};
  // Most candidates do not overlap at all: their boxes in the plane tell before clipping.
  for (int c = 0; c < 2; ++c) {
    auto coord = [c](const P2& q) { return c == 0 ? q.u : q.v; };
    if (std::max({coord(sq[0]), coord(sq[1]), coord(sq[2])}) < std::min({coord(mt[0]), coord(mt[1]), coord(mt[2])}) ||
        std::min({coord(sq[0]), coord(sq[1]), coord(sq[2])}) > std::max({coord(mt[0]), coord(mt[1]), coord(mt[2])}))
      return false;
  }
  if (!(0.5 * std::abs(cross2(sq[0], sq[1], sq[2])) > 1e-12 * s.area)) return false;
  out = {t, m0, n, e1, e2, mt, sq, {h[0], h[1], h[2]}};
  return true;
}

// The quadrature of one slave triangle over its candidates. Each point of the slave triangle
// belongs to one master triangle. Where its projections onto two master faces that are not
// coplanar overlap (a skin triangle wrapped round a convex edge of the block projects onto both
// faces), it belongs to the face it is nearer to, |gap| smaller by more than round-off (coplanar
// neighbours tie and keep their exact partition). Counting it on both added the far face's depth
// to the weighted gap: a skin node lying on the block's face 1.9 mm from its edge got a gap of
// -0.3 mm and was pushed out at the recovery speed, and its pressure was the run's peak.
class SegmentQuadrature {
 public:
  SegmentQuadrature(const SlaveTriangle& s, const std::vector<Candidate>& candidates, const std::vector<std::int32_t>& triangles,
                    std::vector<QuadraturePoint>& points)
      : s_(s), candidates_(candidates), triangles_(triangles), points_(points), tie_(1e-6 * std::sqrt(s.area)) {}

  // The points of candidate ci's overlap with the slave triangle, and whether each slave vertex is
  // over its master triangle (and not nearer another) into `over`.
  void integrate(std::size_t ci, std::array<bool, 3>& over);

 private:
  Vec3 slave_point(const std::array<double, 3>& l) const {
    const double* const* xs = s_.xs;
    return Vec3{l[0] * xs[0][0] + l[1] * xs[1][0] + l[2] * xs[2][0], l[0] * xs[0][1] + l[1] * xs[1][1] + l[2] * xs[2][1],
                l[0] * xs[0][2] + l[1] * xs[1][2] + l[2] * xs[2][2]};
  }
  bool nearer_elsewhere(std::size_t self, const Vec3& xq, double depth) const {
    for (std::size_t o = 0; o < candidates_.size(); ++o) {
      const Candidate& c = candidates_[o];
      if (o == self) continue;
      const Vec3 d = sub(xq.data(), c.m0);
      if (!(std::abs(dot(d, c.n)) < depth - tie_)) continue;
      const auto b = barycentric(P2{dot(d, c.e1), dot(d, c.e2)}, c.mt);
      if (std::min({b[0], b[1], b[2]}) >= 0) return true;
    }
    return false;
  }
  static double height(const Candidate& c, const std::array<double, 3>& l) { return l[0] * c.h[0] + l[1] * c.h[1] + l[2] * c.h[2]; }
  // The point of the slave triangle over q (in ci's plane) is ci's.
  bool belongs(std::size_t ci, const P2& q) const {
    const auto l = barycentric(q, candidates_[ci].sq);
    return !nearer_elsewhere(ci, slave_point(l), std::abs(height(candidates_[ci], l)));
  }
  void add_point(const Candidate& c, const P2& q, double dA) {
    QuadraturePoint qpnt;
    qpnt.lambda = barycentric(q, c.sq), qpnt.mu = barycentric(q, c.mt);
    qpnt.gap = height(c, qpnt.lambda);  // (x_s(q) - x_m(q)) . n
    qpnt.dA = dA;
    qpnt.n = c.n;
    std::copy(&triangles_[3 * c.t], &triangles_[3 * c.t] + 3, qpnt.master.begin());
    points_.push_back(qpnt);
  }
  void fan_triangle(std::size_t ci, bool contested, double to_slave, const P2& a0, const P2& b0, const P2& c0);

  const SlaveTriangle& s_;
  const std::vector<Candidate>& candidates_;
  const std::vector<std::int32_t>& triangles_;
  std::vector<QuadraturePoint>& points_;
  const double tie_;
};

void SegmentQuadrature::integrate(std::size_t ci, std::array<bool, 3>& over) {
  const Candidate& cand = candidates_[ci];
  const std::array<P2, 3>&mt = cand.mt, &sq = cand.sq;
  std::array<P2, 12> poly;
  const int nv = clip_by_triangle(sq.data(), 3, mt, poly);
  if (nv < 3) return;
  const double to_slave = s_.area / (0.5 * std::abs(cross2(sq[0], sq[1], sq[2])));  // dA on the slave per dA in the plane
  bool contested = false;                                                           // is another candidate's plane not this one's?
  for (const Candidate& o : candidates_) contested = contested || dot(o.n, cand.n) < 1 - 1e-9;
  for (int f = 1; f + 1 < nv; ++f)
    fan_triangle(ci, contested, to_slave, poly[0], poly[static_cast<std::size_t>(f)], poly[static_cast<std::size_t>(f + 1)]);
  for (std::size_t v = 0; v < 3; ++v) {  // is the slave vertex itself over this master triangle (and not nearer another)?
    const auto b = barycentric(sq[v], mt);
    if (std::min({b[0], b[1], b[2]}) >= -kOverMasterReach &&
        !(contested && nearer_elsewhere(ci, Vec3{s_.xs[v][0], s_.xs[v][1], s_.xs[v][2]}, std::abs(cand.h[v]))))
      over[v] = true;
  }
}

// One triangle of the clipped polygon's fan, by the edge-midpoint rule (exact: the integrands are
// quadratic). Where the boundary to a nearer face crosses one (its corners and edge midpoints
// disagree), it is split in four, down to kNearerSplits levels, so the quadrature follows the
// boundary. A piece carries whether its corners are this candidate's: its children's corners are
// its corners and edge midpoints, so each split evaluates only the three new midpoints.
void SegmentQuadrature::fan_triangle(std::size_t ci, bool contested, double to_slave, const P2& a0, const P2& b0, const P2& c0) {
  const Candidate& cand = candidates_[ci];
  auto mid = [](const P2& x0, const P2& x1) { return P2{0.5 * (x0.u + x1.u), 0.5 * (x0.v + x1.v)}; };
  struct Piece {
    P2 a, b, c;
    std::array<bool, 3> in;
    int level;
  };
  std::array<Piece, 3 * kNearerSplits + 4> stack;
  int pending = 0;
  stack[static_cast<std::size_t>(pending++)] = {
      a0, b0, c0, contested ? std::array<bool, 3>{belongs(ci, a0), belongs(ci, b0), belongs(ci, c0)} : std::array<bool, 3>{true, true, true}, 0};
  while (pending > 0) {
    const Piece piece = stack[static_cast<std::size_t>(--pending)];
    const double dA = 0.5 * std::abs(cross2(piece.a, piece.b, piece.c)) / 3.0 * to_slave;
    if (!(dA > 0)) continue;
    const P2 m[3] = {mid(piece.a, piece.b), mid(piece.b, piece.c), mid(piece.c, piece.a)};
    if (!contested) {
      for (const P2& q : m) add_point(cand, q, dA);
      continue;
    }
    const std::array<bool, 3> in{belongs(ci, m[0]), belongs(ci, m[1]), belongs(ci, m[2])};
    const bool same = in[0] == in[1] && in[1] == in[2] && piece.in[0] == in[0] && piece.in[1] == in[0] && piece.in[2] == in[0];
    if (same || piece.level == kNearerSplits) {
      for (std::size_t k = 0; k < 3; ++k)
        if (in[k]) add_point(cand, m[k], dA);
      continue;
    }
    const int next = piece.level + 1;
    for (const Piece& child :
         {Piece{piece.a, m[0], m[2], {piece.in[0], in[0], in[2]}, next}, Piece{m[0], piece.b, m[1], {in[0], piece.in[1], in[1]}, next},
          Piece{m[2], m[1], piece.c, {in[2], in[1], piece.in[2]}, next}, Piece{m[0], m[1], m[2], in, next}})
      stack[static_cast<std::size_t>(pending++)] = child;
  }
}

// The mortar segments of slave triangle st with the master triangles near it, integrated.
void MortarSurface::segments_of(const ContactPair& p, const std::vector<std::size_t>& slave_local, std::size_t st, const double* x, double band,
                                const DetectionScratch::Grid& g, std::vector<std::size_t>& seen, SegmentChunk& w) const {
  const std::int32_t* sv = &p.slave_triangles[3 * st];
  SlaveTriangle s{sv, {x + 3 * sv[0], x + 3 * sv[1], x + 3 * sv[2]}, {}, 0};
  const double* const* xs = s.xs;
  int lo[3], hi[3];
  double sb[6];  // the slave triangle's box
  bool outside = false;
  for (int c = 0; c < 3 && !outside; ++c) {
    sb[c] = std::min({xs[0][c], xs[1][c], xs[2][c]}), sb[3 + c] = std::max({xs[0][c], xs[1][c], xs[2][c]});
    outside = sb[3 + c] < g.lo[c] || sb[c] > g.lo[c] + g.cell * g.n[c];
    if (!outside) lo[c] = g.cell_of(sb[c], c), hi[c] = g.cell_of(sb[3 + c], c);
  }
  if (outside) return;  // far from every master triangle
  s.ns = cross(sub(xs[1], xs[0]), sub(xs[2], xs[0]));
  s.area = 0.5 * norm(s.ns);
  if (!(s.area > 0)) return;
  std::vector<Candidate>& candidates = w.candidates;
  candidates.clear();
  Candidate found;
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
          if (master_candidate(s, sb, t, triangles_, x, band, g, found)) candidates.push_back(found);
        }
      }
  if (candidates.empty()) return;
  w.points.clear();
  SegmentQuadrature quadrature(s, candidates, triangles_, w.points);
  std::array<bool, 3> over{false, false, false};
  for (std::size_t ci = 0; ci < candidates.size(); ++ci) quadrature.integrate(ci, over);
  if (w.points.empty()) return;
  TriangleIntegrals ti;
  for (std::size_t v = 0; v < 3; ++v) ti.node[v] = slave_local[3 * st + v];
  ti.over = over;
  integrate_segments(w.points, ti, w.terms);
  w.triangles.push_back(ti);
}

// n . (x_j - sum_k w_k x_k) of a row.
double along_normal(const MortarRow& r, const std::vector<std::int32_t>& masters, const std::vector<double>& weights, const double* x) {
  Vec3 d{x[3 * r.slave_node], x[3 * r.slave_node + 1], x[3 * r.slave_node + 2]};
  for (std::size_t a = r.begin; a < r.end; ++a)
    for (std::size_t c = 0; c < 3; ++c) d[c] += weights[a] * x[3 * masters[a] + static_cast<std::int32_t>(c)];
  return dot(d, r.n);
}

// The pair's rows as integrated, each gap moved on by the row's own kinematics since.
void emit_rows(const DetectionScratch::Mortar& m, std::int32_t pi, const double* x, ContactRows& rows) {
  for (const MortarRow& r : m.rows)
    rows.add(pi, r.slave_index, r.slave_node, m.masters.data() + r.begin, m.weights.data() + r.begin, static_cast<int>(r.end - r.begin), r.n,
             r.gap + along_normal(r, m.masters, m.weights, x) - r.along_normal, r.area);
}

void MortarSurface::detect(const ContactPair& p, std::int32_t pi, const double* x, double band, DetectionScratch& scratch, ContactRows& rows,
                           int threads) const {
  ++scratch.searches;
  DetectionScratch::Mortar& state = scratch.mortar;
  if (state.integrated.holds(x, band, kMortarRefresh * p.search_scale, scratch.moved, threads)) {
    emit_rows(state, pi, x, rows);
    return;
  }
  ++scratch.builds;  // an integration
  DetectionScratch::Grid& g = scratch.grid;
  build_triangle_grid(triangles_, p.search_scale, x, band, g);
  const std::size_t S = p.slave_nodes.size(), T = triangles_.size() / 3, ST = p.slave_triangles.size() / 3;
  std::vector<std::size_t>& local = state.slave_local;  // once per pair
  if (local.size() != p.slave_triangles.size()) {
    local.resize(p.slave_triangles.size());
    for (std::size_t i = 0; i < local.size(); ++i)
      local[i] = static_cast<std::size_t>(std::lower_bound(p.slave_nodes.begin(), p.slave_nodes.end(), p.slave_triangles[i]) - p.slave_nodes.begin());
  }
  // The segment pass in parallel: the slave triangles in kChunks contiguous chunks, taken by the
  // threads as they come (the triangles near the master sit in a few chunks) and added in chunk
  // order below, so the sums do not depend on the thread count.
  const int nt = ST > 2000 ? std::max(threads, 1) : 1;
  const std::size_t chunks = nt > 1 ? kChunks : 1;
  chunks_.resize(chunks);
  seen_.resize(static_cast<std::size_t>(nt));
  for (auto& seen : seen_) seen.assign(T, std::numeric_limits<std::size_t>::max());
#pragma omp parallel for num_threads(nt) schedule(dynamic, 1) if (nt > 1)
  for (std::size_t c = 0; c < chunks; ++c) {
    SegmentChunk& w = chunks_[c];
    w.triangles.clear(), w.terms.clear();
    std::vector<std::size_t>& seen = seen_[static_cast<std::size_t>(nt > 1 ? omp_get_thread_num() : 0)];
    for (std::size_t st = ST * c / chunks; st < ST * (c + 1) / chunks; ++st) segments_of(p, local, st, x, band, g, seen, w);
  }
  std::vector<NodeIntegrals>& node = integrals_;  // kept between steps: no allocation once grown
  node.resize(S);
  for (auto& ni : node) ni.D = 0, ni.G = 0, ni.N = {0, 0, 0}, ni.M.clear();
  std::vector<char>& over = over_;
  over.assign(S, 0);
  for (const SegmentChunk& w : chunks_)
    for (const TriangleIntegrals& ti : w.triangles) {
      for (std::size_t s = 0; s < 3; ++s) {
        NodeIntegrals& ni = node[ti.node[s]];
        ni.D += ti.D[s], ni.G += ti.G[s];
        for (std::size_t d = 0; d < 3; ++d) ni.N[d] += ti.N[s][d];
        if (ti.over[s]) over[ti.node[s]] = 1;
      }
      for (std::size_t i = ti.terms_begin; i < ti.terms_end; ++i)
        node[ti.node[static_cast<std::size_t>(w.terms[i].vertex)]].add_master(w.terms[i].master, w.terms[i].value);
    }
  std::vector<std::int32_t>& masters = state.masters;
  std::vector<double>& weights = state.weights;
  masters.clear(), weights.clear(), state.rows.clear();
  for (std::size_t k = 0; k < S; ++k) {
    const NodeIntegrals& ni = node[k];
    const double nn = norm(ni.N);
    if (!(ni.D > 0) || !(nn > 0)) continue;
    // A node whose own position is beyond the master's edge is held only from in front (behind the
    // plane's extension there is no surface to push it out of).
    if (!over[k] && ni.G < 0) continue;
    // The row's area (its pressure's denominator and its share of the contact area) is the
    // covered area D_j, but at least half the node's tributary area: a node whose tributary hangs
    // over the master's edge is held by that edge, a line load whose pressure the mesh cannot
    // resolve; over the covered sliver alone its pressure grew without bound (2.8 GPa in one step
    // on the hand). A node at least half covered reports r_n / D_j exactly (the patch tests).
    const double area = std::max(ni.D, 0.5 * p.slave_area[k]);
    MortarRow r{static_cast<std::int32_t>(k), p.slave_nodes[k], masters.size(), 0, {ni.N[0] / nn, ni.N[1] / nn, ni.N[2] / nn}, ni.G / ni.D, 0, area};
    for (const auto& [m, v] : ni.M) masters.push_back(m), weights.push_back(-v / ni.D);
    r.end = masters.size();
    r.along_normal = along_normal(r, masters, weights, x);
    state.rows.push_back(r);
  }
  state.integrated.record(p, triangles_, x, band);
  emit_rows(state, pi, x, rows);
}

}  // namespace

std::shared_ptr<const ContactMaster> mortar_surface_master(std::vector<std::int32_t> triangles) {
  return std::make_shared<MortarSurface>(std::move(triangles));
}

}  // namespace tactus::solver
