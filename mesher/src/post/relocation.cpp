// Node relocation (post_passes.hpp): the tets that set the explicit time step, and the tets below
// the mesher's quality guarantees.
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <set>

#include "tactus/core/contracts.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/stable_step.hpp"
#include "tactus/mesher/post_passes.hpp"
#include "tactus/mesher/quality.hpp"
#include "topology.hpp"

namespace tactus::mesher {

namespace {

// Moves single nodes by a pattern search that maximises the worst value of a per-tet measure over
// the node's tets: interior nodes freely, surface nodes in their tangent plane and by at most
// `max_surface_move` from where they started (so the surface approximation is kept), nodes on a
// crease (adjacent surface normals more than p.crease_angle_deg apart) not at all. CGAL's
// perturb/exude leave such tets because all four of their nodes lie on surfaces (skin, bone
// interfaces), where CGAL does not move nodes.
class NodeRelocator {
 public:
  NodeRelocator(TetMesh& mesh, double max_surface_move, const PostPassParams& p)
      : mesh_(mesh), p_(p), max_surface_move_(max_surface_move), tets_of_(tets_around_nodes(mesh)), median_(median_lengths(mesh)) {
    const std::size_t nn = mesh.nodes.size();
    normal_.assign(nn, {0, 0, 0});
    on_surface_.assign(nn, 0), crease_.assign(nn, 0);
    std::vector<std::vector<std::array<double, 3>>> face_normals(nn);
    for (const auto& f : mesh.triangles) {
      const auto n = area_normal(mesh, f);
      const double len = std::sqrt(dot3(n, n));
      if (len == 0) continue;
      for (int i = 0; i < 3; ++i) surface_edges_.insert(edge_key(f[static_cast<std::size_t>(i)], f[static_cast<std::size_t>((i + 1) % 3)]));
      for (int v : f) {
        const auto k = static_cast<std::size_t>(v);
        on_surface_[k] = 1;
        for (std::size_t i = 0; i < 3; ++i) normal_[k][i] += n[i];
        face_normals[k].push_back({n[0] / len, n[1] / len, n[2] / len});
      }
    }
    for (std::size_t k = 0; k < nn; ++k) {
      if (!on_surface_[k]) continue;
      const double len = std::sqrt(dot3(normal_[k], normal_[k]));
      if (len == 0) {  // a node between two coincident, opposite faces: keep it where it is
        crease_[k] = 1;
        continue;
      }
      for (auto& x : normal_[k]) x /= len;
      // Only unsigned agreement matters: a node on two touching surfaces has opposite normals.
      for (const auto& fnrm : face_normals[k])
        if (std::abs(dot3(fnrm, normal_[k])) < std::cos(p.crease_angle_deg * M_PI / 180)) crease_[k] = 1;
    }
    origin_ = mesh.nodes;
  }

  const std::vector<std::vector<std::size_t>>& tets_of() const { return tets_of_; }
  bool crease(std::size_t k) const { return crease_[k]; }
  bool on_surface(std::size_t k) const { return on_surface_[k]; }

  const std::map<int, double>& medians() const { return median_; }
  // L_e over its subdomain's median (negative for an inverted tet).
  double ratio(std::size_t e) const { return tet_length(mesh_, mesh_.tets[e]) / median_.at(mesh_.tet_group[e]); }
  // The smallest dihedral angle (-1 for an inverted tet).
  double min_dihedral(std::size_t e) const { return tet_length(mesh_, mesh_.tets[e]) > 0 ? tet_min_dihedral(mesh_, mesh_.tets[e]) : -1; }
  double worst(std::size_t k, const std::function<double(std::size_t)>& measure) const {
    double q = 1e300;
    for (std::size_t e : tets_of_[k]) q = std::min(q, measure(e));
    return q;
  }

  // The shortfall of the node's tets below `good`, summed.
  double deficit(std::size_t k, const std::function<double(std::size_t)>& measure, double good) const {
    double d = 0;
    for (std::size_t e : tets_of_[k]) d += std::max(0.0, good - measure(e));
    return d;
  }

  // Pattern search on node k along the axes and along the heights of its tets whose measure is
  // below `good`; a move is kept when it raises the worst measure around k and `allowed` holds.
  void improve(std::size_t k, const std::function<double(std::size_t)>& measure, double good, const std::function<bool()>& allowed) {
    if (crease_[k]) return;
    double best = worst(k, measure), best_deficit = deficit(k, measure, good);
    const double h = 0.5 * median_.at(mesh_.tet_group[tets_of_[k].front()]);
    std::vector<std::array<double, 3>> directions = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (std::size_t e : tets_of_[k]) {
      if (measure(e) >= good) continue;
      std::array<int, 3> face{};
      int n = 0;
      for (int v : mesh_.tets[e])
        if (static_cast<std::size_t>(v) != k) face[static_cast<std::size_t>(n++)] = v;
      auto d = area_normal(mesh_, face);
      const double len = std::sqrt(dot3(d, d));
      if (len > 0) directions.push_back({d[0] / len, d[1] / len, d[2] / len});
    }
    double step = 0.3 * h;
    for (int it = 0; it < p_.relocate_iterations && step > 0.01 * h; ++it) {
      bool improved = false;
      for (std::size_t a = 0; a < directions.size() && !improved; ++a)
        for (int sign = -1; sign <= 1 && !improved; sign += 2) {
          std::array<double, 3> d{sign * step * directions[a][0], sign * step * directions[a][1], sign * step * directions[a][2]};
          if (on_surface_[k]) {  // tangential only
            const double dn = dot3(d, normal_[k]);
            for (std::size_t i = 0; i < 3; ++i) d[i] -= dn * normal_[k][i];
          }
          Vec3 trial = mesh_.nodes[k];
          for (std::size_t i = 0; i < 3; ++i) trial[i] += d[i];
          if (on_surface_[k]) {
            std::array<double, 3> total{};
            for (std::size_t i = 0; i < 3; ++i) total[i] = trial[i] - origin_[k][i];
            if (std::sqrt(dot3(total, total)) > max_surface_move_) continue;
          }
          const Vec3 before = mesh_.nodes[k];
          mesh_.nodes[k] = trial;
          const double q = worst(k, measure), q_deficit = deficit(k, measure, good);
          // Better: the worst not lowered and less shortfall over all the node's tets (raising
          // the worst alone could push good tets below `good`; a node whose worst tet it cannot
          // help still helps the others).
          const bool better = q >= best * (1 - 1e-12) && q_deficit < best_deficit * (1 - 1e-6);
          if (better && allowed()) {
            best = q, best_deficit = q_deficit, improved = true;
          } else {
            mesh_.nodes[k] = before;
          }
        }
      if (!improved) step *= 0.5;
    }
  }

  // An edge on no boundary or interface triangle: every tet around it has one label, and its
  // midpoint is an interior node that moves freely.
  bool interior_edge(int a, int b) const { return !surface_edges_.count(edge_key(a, b)); }

  // Splits the edge (a, b) at its midpoint: every tet around it becomes two (the new node takes
  // a's place in one and b's in the other, so both keep the orientation). Returns the new node.
  std::size_t split_edge(int a, int b) {
    Split s;
    const auto ka = static_cast<std::size_t>(a), kb = static_cast<std::size_t>(b);
    std::vector<std::size_t> around;
    for (std::size_t e : tets_of_[ka])
      if (std::count(mesh_.tets[e].begin(), mesh_.tets[e].end(), b)) around.push_back(e);
    s.first_new_tet = mesh_.tets.size();
    for (std::size_t e : around)
      for (int v : mesh_.tets[e]) s.tets_of.emplace(static_cast<std::size_t>(v), tets_of_[static_cast<std::size_t>(v)]);
    const std::size_t m = mesh_.nodes.size();
    Vec3 mid{};
    for (std::size_t i = 0; i < 3; ++i) mid[i] = 0.5 * (mesh_.nodes[ka][i] + mesh_.nodes[kb][i]);
    mesh_.nodes.push_back(mid);
    normal_.push_back({0, 0, 0}), on_surface_.push_back(0), crease_.push_back(0), origin_.push_back(mid), tets_of_.emplace_back();
    for (std::size_t e : around) {
      s.tets.emplace_back(e, mesh_.tets[e]);
      std::array<int, 4> other = mesh_.tets[e];
      std::replace(other.begin(), other.end(), a, static_cast<int>(m));
      std::replace(mesh_.tets[e].begin(), mesh_.tets[e].end(), b, static_cast<int>(m));
      const std::size_t e2 = mesh_.tets.size();
      mesh_.tets.push_back(other), mesh_.tet_group.push_back(mesh_.tet_group[e]);
      std::replace(tets_of_[kb].begin(), tets_of_[kb].end(), e, e2);
      for (int v : other)
        if (v != b && v != static_cast<int>(m)) tets_of_[static_cast<std::size_t>(v)].push_back(e2);
      tets_of_[m].push_back(e), tets_of_[m].push_back(e2);
    }
    last_split_ = std::move(s);
    return m;
  }
  // Takes the last split back.
  void undo_split() {
    for (const auto& [e, t] : last_split_.tets) mesh_.tets[e] = t;
    mesh_.tets.resize(last_split_.first_new_tet), mesh_.tet_group.resize(last_split_.first_new_tet);
    for (auto& [k, list] : last_split_.tets_of) tets_of_[k] = std::move(list);
    mesh_.nodes.pop_back(), normal_.pop_back(), on_surface_.pop_back(), crease_.pop_back(), origin_.pop_back(), tets_of_.pop_back();
  }

 private:
  struct Split {
    std::size_t first_new_tet = 0;
    std::vector<std::pair<std::size_t, std::array<int, 4>>> tets;  // the tets changed, as they were
    std::map<std::size_t, std::vector<std::size_t>> tets_of;       // the tet lists changed, as they were
  };
  static std::pair<int, int> edge_key(int a, int b) { return {std::min(a, b), std::max(a, b)}; }

  TetMesh& mesh_;
  const PostPassParams& p_;
  double max_surface_move_;
  std::vector<std::vector<std::size_t>> tets_of_;
  std::vector<std::array<double, 3>> normal_;
  std::vector<char> on_surface_, crease_;
  std::vector<Vec3> origin_;      // where each node was when the pass began (the surface move is bounded from there)
  std::map<int, double> median_;  // of L_e per group, when the pass began
  std::set<std::pair<int, int>> surface_edges_;
  Split last_split_;
};

}  // namespace

// The tets with the smallest characteristic length L_e relative to their subdomain's median set
// the explicit time step. A move is kept only if it does not bring any incident tet's dihedral
// angle below p.dihedral_floor_deg (or below its current value, if lower already).
void relocate_short_tets(TetMesh& mesh, double max_surface_move, const PostPassParams& p) {
  NodeRelocator r(mesh, max_surface_move, p);
  const auto ratio = [&](std::size_t e) { return r.ratio(e); };
  for (int pass = 0; pass < p.relocate_passes; ++pass) {
    std::set<std::size_t> nodes;
    for (std::size_t e = 0; e < mesh.tets.size(); ++e)
      if (r.ratio(e) < p.relocate_ratio_goal)
        for (int v : mesh.tets[e]) nodes.insert(static_cast<std::size_t>(v));
    if (nodes.empty()) break;
    for (std::size_t k : nodes) {
      const auto dihedral = [&](std::size_t e) { return r.min_dihedral(e); };
      const double angle_floor = std::min(p.dihedral_floor_deg, r.worst(k, dihedral));
      r.improve(k, ratio, p.relocate_ratio_goal, [&] { return r.worst(k, dihedral) >= angle_floor; });
    }
  }
}

// The guarantees as one measure per tet (GuaranteeMeasure, topology.hpp), raised node by node.
std::size_t relocate_poor_tets(TetMesh& mesh, double max_surface_move, const PostPassParams& p) {
  NodeRelocator r(mesh, max_surface_move, p);
  const GuaranteeMeasure guarantee(r.medians(), p);
  const auto measure = [&](std::size_t e) { return guarantee(mesh, mesh.tets[e], mesh.tet_group[e]); };
  auto poor = [&] {
    std::set<std::size_t> nodes;
    for (std::size_t e = 0; e < mesh.tets.size(); ++e)
      if (measure(e) < 1)
        for (int v : mesh.tets[e]) nodes.insert(static_cast<std::size_t>(v));
    return nodes;
  };
  for (int pass = 0; pass < p.relocate_passes; ++pass) {
    const auto nodes = poor();
    if (nodes.empty()) break;
    for (std::size_t k : nodes) r.improve(k, measure, 1.0, [] { return true; });
  }
  // What relocation leaves has its nodes pinned (on creases, or on surfaces it may not leave): a
  // tet whose four nodes lie on surfaces but which has an interior edge (e.g. soft tissue spanning
  // from a bone to the skin) is split there, and the new interior node relocated freely; the split
  // is kept only if it raises the worst measure around that edge and leaves fewer tets below it.
  const auto count_poor = [&] {
    std::size_t n = 0;
    for (std::size_t e = 0; e < mesh.tets.size(); ++e) n += measure(e) < 1;
    return n;
  };
  log::debug() << "poor tets: " << count_poor() << " after relocation";
  for (int round = 0; round < p.split_rounds; ++round) {
    std::size_t splits = 0;
    const std::size_t before_splits = mesh.tets.size();
    for (std::size_t e = 0; e < before_splits; ++e) {
      if (measure(e) >= 1) continue;
      const auto edges = tet_edges_by_length(mesh, mesh.tets[e], true, [&](int x, int y) { return r.interior_edge(x, y); });
      for (const auto& ab : edges) {
        double old_worst = 1e300;
        std::size_t old_poor = 0;
        for (std::size_t o : r.tets_of()[static_cast<std::size_t>(ab.first)])
          if (std::count(mesh.tets[o].begin(), mesh.tets[o].end(), ab.second))
            old_worst = std::min(old_worst, measure(o)), old_poor += measure(o) < 1;
        const std::size_t m = r.split_edge(ab.first, ab.second);
        r.improve(m, measure, 1.0, [] { return true; });
        std::size_t new_poor = 0;
        for (std::size_t o : r.tets_of()[m]) new_poor += measure(o) < 1;
        if (r.worst(m, measure) > old_worst * (1 + 1e-9) && new_poor <= old_poor) {
          ++splits;
          break;
        }
        r.undo_split();
      }
    }
    for (int pass = 0; pass < p.relocate_passes; ++pass) {
      const auto nodes = poor();
      if (nodes.empty()) break;
      for (std::size_t k : nodes) r.improve(k, measure, 1.0, [] { return true; });
    }
    log::debug() << "poor tets: round " << round << ", " << splits << " edges split, " << count_poor() << " left";
    if (splits == 0) break;
  }
  std::size_t left = 0;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    const double d = r.min_dihedral(e);
    if (d >= p.guarantee_dihedral_deg && r.ratio(e) >= p.guarantee_length_ratio) continue;
    ++left;
    int surface = 0, creased = 0;
    for (int v : mesh.tets[e]) surface += r.on_surface(static_cast<std::size_t>(v)), creased += r.crease(static_cast<std::size_t>(v));
    const auto& x = mesh.nodes[static_cast<std::size_t>(mesh.tets[e][0])];
    log::debug() << "poor tet " << e << " group " << mesh.tet_group[e] << " dihedral " << d << " ratio " << r.ratio(e) << " surface nodes " << surface
                 << " crease " << creased << " nodes " << mesh.tets[e][0] << " " << mesh.tets[e][1] << " " << mesh.tets[e][2] << " "
                 << mesh.tets[e][3] << " at " << x[0] * 1e3 << " " << x[1] * 1e3 << " " << x[2] * 1e3 << " mm";
  }
  return left;
}

}  // namespace tactus::mesher
