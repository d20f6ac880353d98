// Contact detection by master kind: the slave nodes near a rigid plane, or near a deformable
// surface (a uniform grid over its triangles as broad phase, the closest projection inside a
// triangle as narrow phase, in parallel over slave nodes), each becoming a constraint row.
#include <algorithm>
#include <cmath>
#include <limits>

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

class DeformableSurface final : public ContactMaster {
 public:
  explicit DeformableSurface(std::vector<std::int32_t> triangles) : triangles_(std::move(triangles)) {}
  std::string describe() const override { return "deformable surface (" + std::to_string(triangles_.size() / 3) + " triangles)"; }
  const std::vector<std::int32_t>& triangles() const override { return triangles_; }
  void detect(const ContactPair& p, std::int32_t pi, const double* x, double band, DetectionScratch& scratch, ContactRows& rows,
              int threads) const override;

 private:
  void build_grid(const ContactPair& p, const double* x, double margin, DetectionScratch::Grid& g) const;
  std::vector<std::int32_t> triangles_;  // 3 per triangle, outward
};

void DeformableSurface::build_grid(const ContactPair& p, const double* x, double margin, DetectionScratch::Grid& g) const {
  build_triangle_grid(triangles_, p.search_scale, x, margin, g);
}

}  // namespace

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
    const std::int32_t* tri = &triangles_[3 * t];
    const double* x0 = x + 3 * tri[0];
    const Vec3 nn = cross(sub(x + 3 * tri[1], x0), sub(x + 3 * tri[2], x0));
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

namespace {

void DeformableSurface::detect(const ContactPair& p, std::int32_t pi, const double* x, double band, DetectionScratch& scratch, ContactRows& rows,
                               int threads) const {
  DetectionScratch::Grid& g = scratch.grid;
  build_grid(p, x, band, g);
  const std::size_t S = p.slave_nodes.size();
  scratch.slot_triangle.assign(S, -1);
  scratch.slot_data.resize(7 * S);
  std::int32_t* slot_t = scratch.slot_triangle.data();
  double* slot = scratch.slot_data.data();
  // Narrow phase per slave node (independent: parallel); rows are gathered in slave order.
#pragma omp parallel for num_threads(threads) schedule(static) if (S > 2000)
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
      const std::int32_t* tri = &triangles_[3 * static_cast<std::size_t>(t)];
      if (tri[0] == s || tri[1] == s || tri[2] == s) continue;
      const double* tn = &g.normal[4 * static_cast<std::size_t>(t)];
      if (tn[3] == 0) continue;  // degenerate triangle
      const Vec3 n{tn[0], tn[1], tn[2]};
      const double *a = x + 3 * tri[0], *b = x + 3 * tri[1], *c = x + 3 * tri[2];
      const double h = dot(sub(xs, a), n);
      if (h > band || h < -band || std::abs(h) >= best_abs) continue;
      // Barycentric coordinates of the projection x_s - h n (signed sub-areas over the area).
      const Vec3 pb = sub(xs, b), pc = sub(xs, c);
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
      const std::int32_t* tri = &triangles_[3 * static_cast<std::size_t>(slot_t[k])];
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

std::shared_ptr<const ContactMaster> deformable_surface_master(std::vector<std::int32_t> triangles) {
  return std::make_shared<DeformableSurface>(std::move(triangles));
}

}  // namespace tactus::solver
