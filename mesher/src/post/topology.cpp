// Mesh adjacency shared by the post-passes, and the boundary triangles rebuilt from the labels.
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <set>

#include "tactus/core/contracts.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/stable_step.hpp"
#include "tactus/mesher/post_passes.hpp"
#include "tactus/mesher/quality.hpp"
#include "topology.hpp"

namespace tactus::mesher {

// The tets around every node.
std::vector<std::vector<std::size_t>> tets_around_nodes(const TetMesh& mesh) {
  std::vector<std::vector<std::size_t>> tets_of(mesh.nodes.size());
  for (std::size_t e = 0; e < mesh.tets.size(); ++e)
    for (int v : mesh.tets[e]) tets_of[static_cast<std::size_t>(v)].push_back(e);
  return tets_of;
}

// Half the cross product of a triangle's edges: its normal (orientation of the triangle) with
// length equal to its area.
std::array<double, 3> area_normal(const TetMesh& mesh, const std::array<int, 3>& f) {
  const Vec3 &a = mesh.nodes[static_cast<std::size_t>(f[0])], &b = mesh.nodes[static_cast<std::size_t>(f[1])],
             &c = mesh.nodes[static_cast<std::size_t>(f[2])];
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  return {0.5 * (u[1] * w[2] - u[2] * w[1]), 0.5 * (u[2] * w[0] - u[0] * w[2]), 0.5 * (u[0] * w[1] - u[1] * w[0])};
}

double tet_length(const TetMesh& mesh, const std::array<int, 4>& t) {
  const TetGradients g = tet_shape_gradients(mesh.nodes[static_cast<std::size_t>(t[0])], mesh.nodes[static_cast<std::size_t>(t[1])],
                                             mesh.nodes[static_cast<std::size_t>(t[2])], mesh.nodes[static_cast<std::size_t>(t[3])]);
  return g.volume > 0 ? characteristic_length(g) : -1.0;
}

double tet_min_dihedral(const TetMesh& mesh, const std::array<int, 4>& t) {
  return tet_quality(mesh.nodes[static_cast<std::size_t>(t[0])], mesh.nodes[static_cast<std::size_t>(t[1])],
                     mesh.nodes[static_cast<std::size_t>(t[2])], mesh.nodes[static_cast<std::size_t>(t[3])])
      .min_dihedral_deg;
}

std::map<int, double> median_lengths(const TetMesh& mesh) {
  std::map<int, std::vector<double>> per;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) per[mesh.tet_group[e]].push_back(tet_length(mesh, mesh.tets[e]));
  std::map<int, double> median;
  for (auto& [g, v] : per) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    median[g] = v[v.size() / 2];
  }
  return median;
}

GuaranteeMeasure::GuaranteeMeasure(std::map<int, double> medians, const PostPassParams& p)
    : median_(std::move(medians)),
      dihedral_goal_(p.guarantee_dihedral_deg * p.guarantee_margin),
      ratio_goal_(p.guarantee_length_ratio * p.guarantee_margin) {}

double GuaranteeMeasure::length_ratio(const TetMesh& mesh, const std::array<int, 4>& t, int group) const {
  const double length = tet_length(mesh, t);
  return length > 0 ? length / median_.at(group) : -1.0;
}

double GuaranteeMeasure::operator()(const TetMesh& mesh, const std::array<int, 4>& t, int group) const {
  const double ratio = length_ratio(mesh, t, group);
  if (ratio < 0) return -1.0;
  return std::min({1.0, tet_min_dihedral(mesh, t) / dihedral_goal_, ratio / ratio_goal_});
}

FaceOwners face_owners(const TetMesh& mesh) {
  FaceOwners owners;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e)
    for (const auto& f : kFaces) owners[tet_face(mesh.tets[e], f)].push_back(e);
  return owners;
}

std::vector<std::size_t> face_fans(const std::vector<std::array<int, 3>>& faces) {
  std::vector<std::size_t> parent(faces.size());
  std::iota(parent.begin(), parent.end(), 0);
  const auto root = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (std::size_t i = 0; i < faces.size(); ++i)
    for (std::size_t j = i + 1; j < faces.size(); ++j) {
      int shared = 0;
      for (int x : faces[i]) shared += std::find(faces[j].begin(), faces[j].end(), x) != faces[j].end();
      if (shared == 2) parent[root(i)] = root(j);  // the node and one more: an edge at the node
    }
  std::map<std::size_t, std::size_t> number;
  std::vector<std::size_t> fan(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) fan[i] = number.emplace(root(i), number.size()).first->second;
  return fan;
}

void keep_alive_tets(TetMesh& mesh, const std::vector<char>& alive) {
  std::vector<std::array<int, 4>> tets;
  std::vector<int> groups;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e)
    if (alive[e]) tets.push_back(mesh.tets[e]), groups.push_back(mesh.tet_group[e]);
  mesh.tets = std::move(tets);
  mesh.tet_group = std::move(groups);
  rebuild_boundary_triangles(mesh);
}

std::array<int, 3> sorted_face(int a, int b, int c) {
  std::array<int, 3> f{a, b, c};
  std::sort(f.begin(), f.end());
  return f;
}

// Boundary triangles from the tets' labels: the faces between different labels (0 = outside),
// skin where one side is outside, bone interface otherwise; oriented out of the higher label
// (soft tissue under the skin, the bone at an interface), as CGAL's facets are above.
void rebuild_boundary_triangles(TetMesh& mesh) {
  const FaceOwners owners = face_owners(mesh);
  mesh.triangles.clear();
  mesh.triangle_group.clear();
  for (const auto& [key, tets] : owners) {
    const int la = mesh.tet_group[tets[0]], lb = tets.size() > 1 ? mesh.tet_group[tets[1]] : 0;
    if (la == lb) continue;
    const std::size_t inner = tets.size() > 1 && lb > la ? tets[1] : tets[0];
    const auto& t = mesh.tets[inner];
    int apex = 0;
    for (int v : t)
      if (v != key[0] && v != key[1] && v != key[2]) apex = v;
    std::array<int, 3> tri = key;
    if (tet_volume(mesh.nodes[static_cast<std::size_t>(tri[0])], mesh.nodes[static_cast<std::size_t>(tri[1])],
                   mesh.nodes[static_cast<std::size_t>(tri[2])], mesh.nodes[static_cast<std::size_t>(apex)]) > 0)
      std::swap(tri[1], tri[2]);  // the apex behind the triangle: its normal points out of `inner`
    mesh.triangles.push_back(tri);
    mesh.triangle_group.push_back(std::min(la, lb) == 0 ? contracts::kSkinTag : contracts::kBoneInterfaceTag);
  }
}

}  // namespace tactus::mesher
