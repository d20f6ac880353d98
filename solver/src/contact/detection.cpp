// Contact detection by master kind: the slave nodes near a rigid plane, or near a deformable
// surface, each becoming a constraint row. For a deformable surface: Verlet lists of candidate
// triangles per slave node (from a uniform grid over the triangles, rebuilt only when a node has
// moved more than half the skin), then, in parallel over slave nodes, the closest point of the
// closed triangles (faces, edges and vertices: a node over a master edge or corner is never lost),
// and a second row where a node sits in a concave corner in front of two master faces.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "detection.hpp"
#include "tactus/solver/contact.hpp"

namespace tactus::solver {

namespace {

class RigidPlane final : public ContactMaster {
 public:
  RigidPlane(const Vec3& point, const Vec3& normal) : point_(point), normal_(normal) {}
  std::string describe() const override { return "rigid plane"; }
  const std::vector<std::int32_t>& triangles() const override {
    static const std::vector<std::int32_t> none;
    return none;
  }
  void detect(const ContactPair& p, std::int32_t pi, const double* x, double band, DetectionScratch&, ContactRows& rows, int) const override {
    for (std::size_t k = 0; k < p.slave_nodes.size(); ++k) {
      const std::int32_t s = p.slave_nodes[k];
      const double h = dot(sub(x + 3 * s, point_.data()), normal_);
      if (h <= band) rows.add(pi, static_cast<std::int32_t>(k), s, nullptr, nullptr, 0, normal_, h, p.slave_area[k]);
    }
  }

 private:
  Vec3 point_, normal_;
};

// Closest point of the closed triangle abc to p, as barycentric weights (each >= 0, summing to 1):
// the Voronoi regions of the vertices, then of the edges, else the face (Ericson, Real-Time
// Collision Detection, 2005, §5.1.5).
std::array<double, 3> closest_on_triangle(const double* p, const double* a, const double* b, const double* c) {
  const Vec3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Vec3 bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Vec3 cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double denom = 1 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return {1 - v - w, v, w};
}

// The unit outward normal of triangle `tri` at positions x, and 1 / (2 area) (all 0 if degenerate),
// into out[0..4).
void store_triangle_normal(const std::int32_t* tri, const double* x, double* out) {
  const double* x0 = x + 3 * tri[0];
  const Vec3 nn = cross(sub(x + 3 * tri[1], x0), sub(x + 3 * tri[2], x0));
  const double twice_area = norm(nn);
  const double inv = twice_area > 0 ? 1.0 / twice_area : 0.0;
  for (int c = 0; c < 3; ++c) out[c] = nn[c] * inv;
  out[3] = inv;
}

class DeformableSurface final : public ContactMaster {
 public:
  DeformableSurface(std::vector<std::int32_t> triangles, bool self_contact);
  std::string describe() const override {
    return std::string(self_ ? "self-contact surface (" : "deformable surface (") + std::to_string(triangles_.size() / 3) + " triangles)";
  }
  const std::vector<std::int32_t>& triangles() const override { return triangles_; }
  void detect(const ContactPair& p, std::int32_t pi, const double* x, double band, DetectionScratch& scratch, ContactRows& rows,
              int threads) const override;

 private:
  bool lists_valid(const double* x, double band, DetectionScratch& s, int threads) const;
  void build_lists(const ContactPair& p, const double* x, double band, DetectionScratch& s, int threads) const;
  void update_normals(const double* x, DetectionScratch& s, int threads) const;
  bool in_ring(std::size_t slave, const std::int32_t* tri) const;

  std::vector<std::int32_t> triangles_;  // 3 per triangle, outward
  // Per triangle, bit e set: its edge from vertex e to vertex e + 1 bounds the master surface (no
  // other triangle shares it); a slave node is held only a little beyond it (kOpenEdgeReach).
  std::vector<std::uint8_t> open_edges_;
  // Self-contact (the slave surface is this one): each slave node's ring (itself and the nodes it
  // shares a triangle with, CSR by slave index) is its own neighbourhood: a triangle touching it
  // is never its master. triangle_slaves_: each triangle's vertices as slave indices.
  bool self_ = false;
  std::vector<std::int32_t> ring_start_, ring_, triangle_slaves_, node_triangle_start_, node_triangles_;
  Vec3 node_normal(std::size_t slave, const double* triangle_normals) const;
};

// How far beyond an open edge of the master surface a slave node still counts as over it, in
// search scales (mean master edges): enough for round-off and for the transverse strain of a
// slave that ends where the master ends (the contact patch test with equal footprints), small
// enough that an overhanging slave is not held up by a surface that is not there.
constexpr double kOpenEdgeReach = 0.05;
// A second master face is a concave corner's other wall when its normal is more than 30 degrees
// from the first face's.
constexpr double kCornerCosine = 0.866;
// Self-contact: a triangle can be the master of a slave node only when they face each other
// (normals more than 120 degrees apart), as the two sides of a fold or two touching fingers do.
constexpr double kFacingCosine = -0.5;
// Self-contact: how deep behind a facing triangle a slave node may be and still be in contact with
// it, in search scales. A node on the back of a finger faces the front of the same finger from
// behind, a whole thickness deep; a node really in contact is held at the surface each step.
constexpr double kSelfContactDepth = 0.25;

DeformableSurface::DeformableSurface(std::vector<std::int32_t> triangles, bool self_contact) : triangles_(std::move(triangles)), self_(self_contact) {
  const std::size_t T = triangles_.size() / 3;
  std::vector<std::pair<std::uint64_t, std::size_t>> edges;  // (edge key, 3 t + e)
  edges.reserve(3 * T);
  for (std::size_t t = 0; t < T; ++t)
    for (std::size_t e = 0; e < 3; ++e) {
      const auto a = static_cast<std::uint64_t>(triangles_[3 * t + e]), b = static_cast<std::uint64_t>(triangles_[3 * t + (e + 1) % 3]);
      edges.emplace_back(std::min(a, b) << 32 | std::max(a, b), 3 * t + e);
    }
  std::sort(edges.begin(), edges.end());
  open_edges_.assign(T, 0);
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    if (j - i == 1) open_edges_[edges[i].second / 3] |= static_cast<std::uint8_t>(1u << (edges[i].second % 3));
    i = j;
  }
  if (!self_) return;
  // The slave nodes of a self-contact pair are this surface's vertices in ascending order (set_slave_surface).
  std::vector<std::int32_t> nodes(triangles_.begin(), triangles_.end());
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  triangle_slaves_.resize(triangles_.size());
  for (std::size_t i = 0; i < triangles_.size(); ++i)
    triangle_slaves_[i] = static_cast<std::int32_t>(std::lower_bound(nodes.begin(), nodes.end(), triangles_[i]) - nodes.begin());
  std::vector<std::pair<std::int32_t, std::int32_t>> ring;  // (slave index, node)
  for (std::size_t t = 0; t < T; ++t)
    for (std::size_t a = 0; a < 3; ++a)
      for (std::size_t b = 0; b < 3; ++b) ring.emplace_back(triangle_slaves_[3 * t + a], triangles_[3 * t + b]);
  std::sort(ring.begin(), ring.end());
  ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  ring_start_.assign(nodes.size() + 1, 0);
  for (const auto& [k, v] : ring) ++ring_start_[static_cast<std::size_t>(k) + 1], ring_.push_back(v);
  for (std::size_t k = 0; k < nodes.size(); ++k) ring_start_[k + 1] += ring_start_[k];
  node_triangle_start_.assign(nodes.size() + 1, 0);
  for (std::int32_t k : triangle_slaves_) ++node_triangle_start_[static_cast<std::size_t>(k) + 1];
  for (std::size_t k = 0; k < nodes.size(); ++k) node_triangle_start_[k + 1] += node_triangle_start_[k];
  node_triangles_.resize(triangle_slaves_.size());
  std::vector<std::int32_t> at(node_triangle_start_.begin(), node_triangle_start_.end() - 1);
  for (std::size_t i = 0; i < triangle_slaves_.size(); ++i)
    node_triangles_[static_cast<std::size_t>(at[static_cast<std::size_t>(triangle_slaves_[i])]++)] = static_cast<std::int32_t>(i / 3);
}

// A self-contact slave node's outward normal: its triangles' normals weighted by their areas,
// from the triangle normals of this step (4 per triangle: n, 1 / (2 area)).
Vec3 DeformableSurface::node_normal(std::size_t slave, const double* tn) const {
  Vec3 n{0, 0, 0};
  for (auto i = node_triangle_start_[slave]; i < node_triangle_start_[slave + 1]; ++i) {
    const double* t = tn + 4 * static_cast<std::size_t>(node_triangles_[static_cast<std::size_t>(i)]);
    const double twice_area = t[3] > 0 ? 1.0 / t[3] : 0.0;
    for (int c = 0; c < 3; ++c) n[c] += twice_area * t[c];
  }
  const double l = norm(n);
  return l > 0 ? Vec3{n[0] / l, n[1] / l, n[2] / l} : n;
}

bool DeformableSurface::in_ring(std::size_t slave, const std::int32_t* tri) const {
  for (auto i = ring_start_[slave]; i < ring_start_[slave + 1]; ++i) {
    const std::int32_t v = ring_[static_cast<std::size_t>(i)];
    if (v == tri[0] || v == tri[1] || v == tri[2]) return true;
  }
  return false;
}

}  // namespace

void BuildSnapshot::record(const ContactPair& p, const std::vector<std::int32_t>& master_triangles, const double* x_now, double band_now) {
  if (nodes.empty()) {  // the topology does not change: once
    nodes.assign(p.slave_nodes.begin(), p.slave_nodes.end());
    nodes.insert(nodes.end(), master_triangles.begin(), master_triangles.end());
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  }
  x.resize(3 * nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i)
    for (int c = 0; c < 3; ++c) x[3 * i + c] = x_now[3 * nodes[i] + c];
  band = band_now;
  moved_bound = 0, unscanned = 0;
}

bool BuildSnapshot::holds(const double* x_now, double band_now, double reach, double moved, int threads) {
  if (band != band_now || x.empty()) return false;
  moved_bound += moved;  // the triangle inequality over the checks since the last scan
  if (moved_bound <= kBoundSlack * reach && ++unscanned < kMaxUnscanned) return true;
  ++scans, unscanned = 0;
  const std::size_t n = nodes.size();
  const std::int32_t* ids = nodes.data();
  const double* x0 = x.data();
  double worst = 0;
#pragma omp parallel for num_threads(threads) schedule(static) reduction(max : worst) if (n > 20000)
  for (std::size_t i = 0; i < n; ++i) {
    const double* xi = x_now + 3 * ids[i];
    const double dx = xi[0] - x0[3 * i], dy = xi[1] - x0[3 * i + 1], dz = xi[2] - x0[3 * i + 2];
    worst = std::max(worst, dx * dx + dy * dy + dz * dz);
  }
  moved_bound = std::sqrt(worst);
  return worst <= reach * reach;
}

void build_triangle_grid(const std::vector<std::int32_t>& triangles_, double scale, const double* x, double margin, DetectionScratch::Grid& g) {
  const std::size_t T = triangles_.size() / 3;
  double lo[3], hi[3];
  for (int c = 0; c < 3; ++c) lo[c] = std::numeric_limits<double>::infinity(), hi[c] = -lo[c];
  for (std::int32_t v : triangles_)
    for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], x[3 * v + c]), hi[c] = std::max(hi[c], x[3 * v + c]);
  for (int c = 0; c < 3; ++c) lo[c] -= margin, hi[c] += margin;
  // Cells about one master edge wide, at most ~8 per triangle (a flat surface in a large box).
  double cell = std::max(scale, 2 * margin);
  const double budget = 8.0 * static_cast<double>(T) + 64;
  while ((std::ceil((hi[0] - lo[0]) / cell) * std::ceil((hi[1] - lo[1]) / cell) * std::ceil((hi[2] - lo[2]) / cell)) > budget) cell *= 1.26;
  g.cell = cell;
  for (int c = 0; c < 3; ++c) g.lo[c] = lo[c], g.n[c] = std::max(1, static_cast<int>(std::ceil((hi[c] - lo[c]) / cell)));
  const std::size_t cells = static_cast<std::size_t>(g.n[0]) * g.n[1] * g.n[2];
  g.count.assign(cells + 1, 0);
  g.box.resize(T);
  g.extent.resize(6 * T);
  g.normal.resize(4 * T);
  for (std::size_t t = 0; t < T; ++t) {
    double a[3], b[3];
    for (int c = 0; c < 3; ++c) a[c] = std::numeric_limits<double>::infinity(), b[c] = -a[c];
    for (int k = 0; k < 3; ++k) {
      const double* xv = x + 3 * triangles_[3 * t + k];
      for (int c = 0; c < 3; ++c) a[c] = std::min(a[c], xv[c]), b[c] = std::max(b[c], xv[c]);
    }
    auto& bx = g.box[t];
    for (int c = 0; c < 3; ++c) bx[c] = g.cell_of(a[c] - margin, c), bx[3 + c] = g.cell_of(b[c] + margin, c);
    std::copy(a, a + 3, &g.extent[6 * t]), std::copy(b, b + 3, &g.extent[6 * t + 3]);
    store_triangle_normal(&triangles_[3 * t], x, &g.normal[4 * t]);
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

namespace {

// The lists stay valid while the band is the one they were built for and no node of the pair has
// moved more than skin / 2 since: a triangle point moves at most as far as its farthest vertex, so
// a slave node and any master point have closed in by at most the skin.
bool DeformableSurface::lists_valid(const double* x, double band, DetectionScratch& s, int threads) const {
  return s.skin > 0 && s.built.holds(x, band, 0.5 * s.skin, s.moved, threads);
}

// Candidates of each slave node: the triangles in its grid cell whose bounding box grown by
// band + skin holds it.
void DeformableSurface::build_lists(const ContactPair& p, const double* x, double band, DetectionScratch& s, int threads) const {
  const double reach = band + s.skin;
  DetectionScratch::Grid& g = s.grid;
  build_triangle_grid(triangles_, p.search_scale, x, reach, g);
  s.built.record(p, triangles_, x, band);
  ++s.builds;
  const std::size_t S = p.slave_nodes.size();
  s.candidate_start.assign(S + 1, 0);
  // Never a candidate: a triangle of the node itself, and for self-contact one touching its ring
  // (both fixed by the topology) or one turned towards the node's side by more than 60 degrees past
  // the facing limit (no part turns that far while its nodes move half the skin).
  auto visit = [&](std::size_t k, auto&& take) {
    const std::int32_t node = p.slave_nodes[k];
    const double* xs = x + 3 * node;
    std::size_t cell = 0;
    for (int c = 2; c >= 0; --c) {
      const double f = (xs[c] - g.lo[c]) / g.cell;
      if (!(f >= 0 && f < g.n[c])) return;
      cell = cell * static_cast<std::size_t>(g.n[c]) + static_cast<std::size_t>(f);
    }
    const Vec3 sn = self_ ? node_normal(k, g.normal.data()) : Vec3{0, 0, 0};
    for (std::int32_t it = g.count[cell]; it < g.start[cell]; ++it) {
      const std::int32_t t = g.items[static_cast<std::size_t>(it)];
      const std::int32_t* tri = &triangles_[3 * static_cast<std::size_t>(t)];
      bool near = self_ ? !in_ring(k, tri) : tri[0] != node && tri[1] != node && tri[2] != node;
      for (int c = 0; c < 3 && near; ++c) {
        const double a = x[3 * tri[0] + c], b = x[3 * tri[1] + c], d = x[3 * tri[2] + c];
        near = xs[c] >= std::min({a, b, d}) - reach && xs[c] <= std::max({a, b, d}) + reach;
      }
      if (near && self_) {
        const double* tn = &g.normal[4 * static_cast<std::size_t>(t)];
        near = dot({tn[0], tn[1], tn[2]}, sn) < kFacingCosine + 1.0;
      }
      if (near) take(t);
    }
  };
  std::int32_t* start = s.candidate_start.data();
#pragma omp parallel for num_threads(threads) schedule(static) if (S > 2000)
  for (std::size_t k = 0; k < S; ++k) visit(k, [&](std::int32_t) { ++start[k + 1]; });
  for (std::size_t k = 0; k < S; ++k) start[k + 1] += start[k];
  s.candidates.resize(static_cast<std::size_t>(start[S]));
  std::int32_t* out = s.candidates.data();
#pragma omp parallel for num_threads(threads) schedule(static) if (S > 2000)
  for (std::size_t k = 0; k < S; ++k) {
    std::int32_t at = start[k];
    visit(k, [&](std::int32_t t) { out[at++] = t; });
  }
  // The triangles whose normals later steps need: the candidates, and for self-contact the
  // triangles around each slave node that has candidates (its own normal).
  std::vector<std::int32_t>& active = s.active_triangles;
  active.assign(s.candidates.begin(), s.candidates.end());
  if (self_)
    for (std::size_t k = 0; k < S; ++k)
      if (start[k] < start[k + 1])
        for (auto i = node_triangle_start_[k]; i < node_triangle_start_[k + 1]; ++i) active.push_back(node_triangles_[static_cast<std::size_t>(i)]);
  std::sort(active.begin(), active.end());
  active.erase(std::unique(active.begin(), active.end()), active.end());
}

// Unit outward normals (4 per triangle: n, 1 / (2 area); 0 if degenerate) of the triangles the
// lists use; the others' stay as the last build left them.
void DeformableSurface::update_normals(const double* x, DetectionScratch& s, int threads) const {
  double* tn = s.grid.normal.data();
  const std::size_t A = s.active_triangles.size();
  const std::int32_t* active = s.active_triangles.data();
#pragma omp parallel for num_threads(threads) schedule(static) if (A > 20000)
  for (std::size_t i = 0; i < A; ++i) {
    const auto t = static_cast<std::size_t>(active[i]);
    store_triangle_normal(&triangles_[3 * t], x, tn + 4 * t);
  }
}

void DeformableSurface::detect(const ContactPair& p, std::int32_t pi, const double* x, double band, DetectionScratch& scratch, ContactRows& rows,
                               int threads) const {
  ++scratch.searches;
  if (lists_valid(x, band, scratch, threads))
    update_normals(x, scratch, threads);
  else
    build_lists(p, x, band, scratch, threads);  // (the grid computes every triangle's normal)
  const std::size_t S = p.slave_nodes.size();
  scratch.slot_triangle.assign(2 * S, -1);
  scratch.slot_data.resize(14 * S);
  std::int32_t* slot_t = scratch.slot_triangle.data();
  double* slot = scratch.slot_data.data();
  const std::int32_t* cand_start = scratch.candidate_start.data();
  const std::int32_t* cand = scratch.candidates.data();
  const double* tnormal = scratch.grid.normal.data();
  const double self_depth = kSelfContactDepth * p.search_scale;
  const double open_reach = kOpenEdgeReach * p.search_scale, tie = 1e-12 * p.search_scale * p.search_scale;
  // Narrow phase per slave node (independent: parallel); rows are gathered in slave order.
#pragma omp parallel for num_threads(threads) schedule(static) if (S > 20000)
  for (std::size_t k = 0; k < S; ++k) {
    const std::int32_t s = p.slave_nodes[k];
    const double* xs = x + 3 * s;
    // The closest point of the closed master triangles; at equal distance (a node over a convex
    // edge or corner) the face the node is most in front of.
    double best_d2 = std::numeric_limits<double>::infinity(), best_h = 0;
    double* out = slot + 14 * k;
    if (cand_start[k] == cand_start[k + 1]) continue;
    const Vec3 sn = self_ ? node_normal(k, tnormal) : Vec3{0, 0, 0};
    for (std::int32_t it = cand_start[k]; it < cand_start[k + 1]; ++it) {
      const std::int32_t t = cand[it];
      const std::int32_t* tri = &triangles_[3 * static_cast<std::size_t>(t)];
      const double* tn = tnormal + 4 * static_cast<std::size_t>(t);
      if (tn[3] == 0) continue;  // degenerate triangle
      const Vec3 n{tn[0], tn[1], tn[2]};
      if (self_ && dot(n, sn) > kFacingCosine) continue;
      const double *a = x + 3 * tri[0], *b = x + 3 * tri[1], *c = x + 3 * tri[2];
      const double h = dot(sub(xs, a), n);
      if (h > band || h < (self_ ? -std::min(band, self_depth) : -band)) continue;
      const std::array<double, 3> w = closest_on_triangle(xs, a, b, c);
      const Vec3 d{xs[0] - (w[0] * a[0] + w[1] * b[0] + w[2] * c[0]), xs[1] - (w[0] * a[1] + w[1] * b[1] + w[2] * c[1]),
                   xs[2] - (w[0] * a[2] + w[1] * b[2] + w[2] * c[2])};
      const double d2 = dot(d, d), lateral = std::sqrt(std::max(0.0, d2 - h * h));
      // Beyond an edge or vertex of the triangle: in front of a convex edge or corner (the wedge
      // between its faces) up to the band; beyond an open edge of the surface (its opposite vertex's
      // weight 0), or behind the plane, only a little: a node that has sunk in lies under a face
      // (it came through one), and one behind a ridge of a thin part is not in contact with its
      // far side.
      const unsigned open = open_edges_[static_cast<std::size_t>(t)];
      const bool at_open_edge = ((open & 1u) && w[2] == 0) || ((open & 2u) && w[0] == 0) || ((open & 4u) && w[1] == 0);
      if (lateral > (at_open_edge || h < 0 ? open_reach : band)) continue;
      if (d2 > best_d2 + tie || (d2 >= best_d2 - tie && h <= best_h)) continue;
      best_d2 = d2, best_h = h;
      slot_t[2 * k] = t;
      out[0] = w[0], out[1] = w[1], out[2] = w[2], out[3] = n[0], out[4] = n[1], out[5] = n[2], out[6] = h;
    }
    if (slot_t[2 * k] < 0) continue;
    // A concave corner: the nearest other face the node is in front of (projection inside it),
    // turned by more than 30 degrees from the first: both walls hold the node.
    const Vec3 n0{out[3], out[4], out[5]};
    double best2 = std::numeric_limits<double>::infinity();
    for (std::int32_t it = cand_start[k]; it < cand_start[k + 1]; ++it) {
      const std::int32_t t = cand[it];
      const std::int32_t* tri = &triangles_[3 * static_cast<std::size_t>(t)];
      const double* tn = tnormal + 4 * static_cast<std::size_t>(t);
      if (t == slot_t[2 * k] || tn[3] == 0) continue;
      const Vec3 n{tn[0], tn[1], tn[2]};
      if (dot(n, n0) > kCornerCosine || (self_ && dot(n, sn) > kFacingCosine)) continue;
      const double *a = x + 3 * tri[0], *b = x + 3 * tri[1], *c = x + 3 * tri[2];
      const double h = dot(sub(xs, a), n);
      if (h < 0 || h > band || h >= best2) continue;
      const Vec3 pb = sub(xs, b), pc = sub(xs, c);  // barycentric by signed sub-areas: inside all three edges
      const double la = dot(cross(sub(c, b), pb), n) * tn[3], lb = dot(cross(sub(a, c), pc), n) * tn[3], lc = 1.0 - la - lb;
      if (la < 0 || lb < 0 || lc < 0) continue;
      best2 = h;
      slot_t[2 * k + 1] = t;
      double* o2 = out + 7;
      o2[0] = la, o2[1] = lb, o2[2] = lc, o2[3] = n[0], o2[4] = n[1], o2[5] = n[2], o2[6] = h;
    }
  }
  for (std::size_t k = 0; k < S; ++k)
    for (std::size_t j = 0; j < 2; ++j)
      if (slot_t[2 * k + j] >= 0) {
        const double* d = slot + 14 * k + 7 * j;
        const std::int32_t* tri = &triangles_[3 * static_cast<std::size_t>(slot_t[2 * k + j])];
        const double w[3] = {-d[0], -d[1], -d[2]};  // -r shared over the triangle with N_i
        rows.add(pi, static_cast<std::int32_t>(k), p.slave_nodes[k], tri, w, 3, {d[3], d[4], d[5]}, d[6], p.slave_area[k]);
      }
}

}  // namespace

void ContactRows::clear() {
  pair.clear(), slave_index.clear(), start.assign(1, 0), nodes.clear(), weights.clear(), normal.clear(), gap.clear(), area.clear();
  reaction.clear(), compliance.clear(), status.clear();
}

void ContactRows::add(std::int32_t pair_index, std::int32_t slave_i, std::int32_t slave_node, const std::int32_t* master_nodes,
                      const double* master_weights, int masters, const Vec3& n, double h, double a) {
  pair.push_back(pair_index);
  slave_index.push_back(slave_i);
  nodes.push_back(slave_node);
  weights.push_back(1.0);
  for (int i = 0; i < masters; ++i) nodes.push_back(master_nodes[i]), weights.push_back(master_weights[i]);
  start.push_back(static_cast<std::int32_t>(nodes.size()));
  normal.insert(normal.end(), n.begin(), n.end());
  gap.push_back(h);
  area.push_back(a);
}

std::shared_ptr<const ContactMaster> rigid_plane_master(const Vec3& point, const Vec3& outward_normal) {
  return std::make_shared<RigidPlane>(point, outward_normal);
}

std::shared_ptr<const ContactMaster> deformable_surface_master(std::vector<std::int32_t> triangles, bool self_contact) {
  return std::make_shared<DeformableSurface>(std::move(triangles), self_contact);
}

}  // namespace tactus::solver
