// Collapsing short surface edges of the tets below the guarantees (post_passes.hpp). Relocation
// moves surface nodes only within the surface and edge splits only add interior nodes, so a tet
// whose four nodes crowd one surface (two surface nodes a fraction of the facet size apart, a small
// fold of CGAL's surface) stays. Merging one of the two nodes into the other removes the tets around
// their edge and stretches the rest; it is done only when every tet stays positive, the worst
// measure around the two nodes rises and fewer tets are below it, no surface triangle turns over,
// the removed node lies within `max_surface_move` of every surface triangle that replaces it, and
// the two nodes' neighbourhoods meet only around their edge (the link condition: the mesh and its
// surfaces stay manifold).
#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "tactus/core/contracts.hpp"
#include "tactus/core/log.hpp"
#include "tactus/mesher/post_passes.hpp"
#include "topology.hpp"

namespace tactus::mesher {

namespace {

class SurfaceEdgeCollapser {
 public:
  SurfaceEdgeCollapser(TetMesh& mesh, double max_surface_move, const PostPassParams& p)
      : mesh_(mesh),
        max_move_(max_surface_move),
        measure_(mesh, p),
        tets_of_(tets_around_nodes(mesh)),
        tris_of_(mesh.nodes.size()),
        tet_alive_(mesh.tets.size(), 1),
        tri_alive_(mesh.triangles.size(), 1),
        node_alive_(mesh.nodes.size(), 1),
        labels_(mesh.nodes.size()) {
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      for (int v : mesh.triangles[t]) tris_of_[static_cast<std::size_t>(v)].push_back(t);
    for (std::size_t e = 0; e < mesh.tets.size(); ++e)
      for (int v : mesh.tets[e]) labels_[static_cast<std::size_t>(v)].insert(mesh.tet_group[e]);
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)  // a skin node borders the outside
      if (mesh.triangle_group[t] == contracts::kSkinTag)
        for (int v : mesh.triangles[t]) labels_[static_cast<std::size_t>(v)].insert(0);
  }

  std::size_t run() {
    std::size_t collapsed = 0;
    const std::size_t n = mesh_.tets.size();
    for (std::size_t e = 0; e < n; ++e) {
      if (!tet_alive_[e] || measure(e) >= 1) continue;
      bool done = false;
      for (const auto& [a, b] : tet_edges_by_length(mesh_, mesh_.tets[e], false, [&](int x, int y) { return surface_edge(x, y); }))
        if ((done = try_collapse(b, a) || try_collapse(a, b))) break;
      collapsed += done;
    }
    if (collapsed > 0) compact();
    return collapsed;
  }

 private:
  const Vec3& node(int v) const { return mesh_.nodes[static_cast<std::size_t>(v)]; }
  double measure(std::size_t e) const { return measure_(mesh_, mesh_.tets[e], mesh_.tet_group[e]); }

  bool surface_edge(int a, int b) const {
    for (std::size_t t : tris_of_[static_cast<std::size_t>(a)])
      if (tri_alive_[t] && std::count(mesh_.triangles[t].begin(), mesh_.triangles[t].end(), b)) return true;
    return false;
  }

  // The nodes that share an element (of `elements`, alive) with both a and b share one that holds
  // both: merging b into a then pinches nothing.
  template <class Element>
  static bool link_condition(const std::vector<std::vector<std::size_t>>& of, const std::vector<char>& alive, const std::vector<Element>& elements,
                             int a, int b) {
    std::set<int> near_a, near_b, around_edge;
    for (std::size_t e : of[static_cast<std::size_t>(a)])
      if (alive[e])
        for (int v : elements[e]) near_a.insert(v);
    for (std::size_t e : of[static_cast<std::size_t>(b)]) {
      if (!alive[e]) continue;
      const bool has_a = std::count(elements[e].begin(), elements[e].end(), a) > 0;
      for (int v : elements[e]) {
        near_b.insert(v);
        if (has_a) around_edge.insert(v);
      }
    }
    for (int v : near_b)
      if (v != a && v != b && near_a.count(v) && !around_edge.count(v)) return false;
    return true;
  }

  // Merges node b into node a if that is allowed and better (see the file's comment).
  bool try_collapse(int b, int a) {
    const auto ka = static_cast<std::size_t>(a), kb = static_cast<std::size_t>(b);
    // a takes b's place on every surface b is on.
    if (!std::includes(labels_[ka].begin(), labels_[ka].end(), labels_[kb].begin(), labels_[kb].end())) return false;
    // Link condition: the nodes next to both a and b are those of the tets around the edge ab;
    // on the surface, those of its triangles.
    if (!link_condition(tets_of_, tet_alive_, mesh_.tets, a, b) || !link_condition(tris_of_, tri_alive_, mesh_.triangles, a, b)) return false;
    // Before: the worst measure and the tets below it around a and b.
    std::set<std::size_t> around;
    for (std::size_t e : tets_of_[ka])
      if (tet_alive_[e]) around.insert(e);
    for (std::size_t e : tets_of_[kb])
      if (tet_alive_[e]) around.insert(e);
    double worst_before = 1e300;
    std::size_t poor_before = 0;
    for (std::size_t e : around) {
      const double q = measure(e);
      worst_before = std::min(worst_before, q), poor_before += q < 1;
    }
    // After: b's tets without a, with a in b's place.
    double worst_after = 1e300;
    std::size_t poor_after = 0;
    for (std::size_t e : around) {
      auto t = mesh_.tets[e];
      if (std::count(t.begin(), t.end(), a) && std::count(t.begin(), t.end(), b)) continue;  // removed
      std::replace(t.begin(), t.end(), b, a);
      const double q = measure_(mesh_, t, mesh_.tet_group[e]);
      if (q <= 0) return false;
      worst_after = std::min(worst_after, q), poor_after += q < 1;
    }
    if (!(worst_after > worst_before * (1 + 1e-9) && poor_after < poor_before)) return false;
    // The surface: no triangle turns over, and b stays within max_move of each that replaces it.
    for (std::size_t t : tris_of_[kb]) {
      if (!tri_alive_[t]) continue;
      auto f = mesh_.triangles[t];
      if (std::count(f.begin(), f.end(), a)) continue;  // removed
      const auto before = area_normal(mesh_, f);
      std::replace(f.begin(), f.end(), b, a);
      const auto after = area_normal(mesh_, f);
      const double len = std::sqrt(dot3(after, after));
      if (len == 0 || dot3(before, after) <= 0) return false;
      const Vec3& x = node(b);
      const Vec3& y = node(a);
      const std::array<double, 3> d{x[0] - y[0], x[1] - y[1], x[2] - y[2]};
      if (std::abs(dot3(d, after)) / len > max_move_) return false;
    }
    apply(b, a);
    return true;
  }

  void apply(int b, int a) {
    merge_node(mesh_.tets, tets_of_, tet_alive_, b, a);
    merge_node(mesh_.triangles, tris_of_, tri_alive_, b, a);
    node_alive_[static_cast<std::size_t>(b)] = 0;
  }

  // Node b becomes a in `elements`: those holding both die, the others move to a's list.
  template <class Element>
  static void merge_node(std::vector<Element>& elements, std::vector<std::vector<std::size_t>>& of, std::vector<char>& alive, int b, int a) {
    for (std::size_t e : of[static_cast<std::size_t>(b)]) {
      if (!alive[e]) continue;
      Element& el = elements[e];
      if (std::count(el.begin(), el.end(), a)) {
        alive[e] = 0;
      } else {
        std::replace(el.begin(), el.end(), b, a);
        of[static_cast<std::size_t>(a)].push_back(e);
      }
    }
    of[static_cast<std::size_t>(b)].clear();
  }

  // Drops the removed tets, triangles and nodes and renumbers the nodes.
  void compact() {
    std::vector<int> id(mesh_.nodes.size(), -1);
    std::vector<Vec3> nodes;
    for (std::size_t k = 0; k < mesh_.nodes.size(); ++k)
      if (node_alive_[k]) id[k] = static_cast<int>(nodes.size()), nodes.push_back(mesh_.nodes[k]);
    mesh_.nodes = std::move(nodes);
    keep_alive(mesh_.tets, mesh_.tet_group, tet_alive_, id);
    keep_alive(mesh_.triangles, mesh_.triangle_group, tri_alive_, id);
  }

  // The live elements (and their groups), their nodes renumbered by `id`.
  template <class Element>
  static void keep_alive(std::vector<Element>& elements, std::vector<int>& groups, const std::vector<char>& alive, const std::vector<int>& id) {
    std::size_t kept = 0;
    for (std::size_t e = 0; e < elements.size(); ++e) {
      if (!alive[e]) continue;
      for (int& v : elements[e]) v = id[static_cast<std::size_t>(v)];
      elements[kept] = elements[e], groups[kept] = groups[e], ++kept;
    }
    elements.resize(kept), groups.resize(kept);
  }

  TetMesh& mesh_;
  double max_move_;
  GuaranteeMeasure measure_;
  std::vector<std::vector<std::size_t>> tets_of_, tris_of_;
  std::vector<char> tet_alive_, tri_alive_, node_alive_;
  std::vector<std::set<int>> labels_;  // the labels of the tets around each node (0: the outside, on the skin)
};

}  // namespace

std::size_t collapse_poor_surface_edges(TetMesh& mesh, double max_surface_move, const PostPassParams& p) {
  return SurfaceEdgeCollapser(mesh, max_surface_move, p).run();
}

}  // namespace tactus::mesher
