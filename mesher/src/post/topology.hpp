#pragma once
// Face keys, the faces of a tet, and the guarantee measure, for the post-passes.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "tactus/core/mesh.hpp"
#include "tactus/mesher/post_passes.hpp"

namespace tactus::mesher {

std::array<int, 3> sorted_face(int a, int b, int c);
inline constexpr int kFaces[4][4] = {{1, 2, 3, 0}, {0, 2, 3, 1}, {0, 1, 3, 2}, {0, 1, 2, 3}};  // face nodes, then the opposite
// The key of face f (a row of kFaces) of tet t.
inline std::array<int, 3> tet_face(const std::array<int, 4>& t, const int (&f)[4]) { return sorted_face(t[f[0]], t[f[1]], t[f[2]]); }
// The fan (0, 1, ..) of each of these faces, all through one node: faces sharing an edge at the
// node are in one fan (a boundary is a 2-manifold at the node when there is one fan).
std::vector<std::size_t> face_fans(const std::vector<std::array<int, 3>>& faces);

// Keeps the tets whose `alive` is set (in order) and rebuilds the boundary triangles.
void keep_alive_tets(TetMesh& mesh, const std::vector<char>& alive);

// The tets on each face, by key.
using FaceOwners = std::map<std::array<int, 3>, std::vector<std::size_t>>;
FaceOwners face_owners(const TetMesh& mesh);

inline double dot3(const std::array<double, 3>& a, const std::array<double, 3>& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// A tet's characteristic length L_e (core's stable-step function; -1 when it is inverted or flat)
// and its smallest dihedral angle in degrees.
double tet_length(const TetMesh& mesh, const std::array<int, 4>& tet);
double tet_min_dihedral(const TetMesh& mesh, const std::array<int, 4>& tet);
// The median L_e of each volume group's tets.
std::map<int, double> median_lengths(const TetMesh& mesh);

// The edges (a, b) of a tet that `keep` accepts, shortest first or longest first.
template <class Keep>
std::vector<std::pair<int, int>> tet_edges_by_length(const TetMesh& mesh, const std::array<int, 4>& tet, bool longest_first, Keep keep) {
  std::vector<std::pair<double, std::pair<int, int>>> edges;
  for (std::size_t i = 0; i < 4; ++i)
    for (std::size_t j = i + 1; j < 4; ++j) {
      const int a = tet[i], b = tet[j];
      if (!keep(a, b)) continue;
      const Vec3& xa = mesh.nodes[static_cast<std::size_t>(a)];
      const Vec3& xb = mesh.nodes[static_cast<std::size_t>(b)];
      const double len = std::hypot(xa[0] - xb[0], xa[1] - xb[1], xa[2] - xb[2]);
      edges.push_back({longest_first ? -len : len, {a, b}});
    }
  std::sort(edges.begin(), edges.end());
  std::vector<std::pair<int, int>> out;
  for (const auto& [len, ab] : edges) out.push_back(ab);
  return out;
}

// The guarantees (PostPassParams) as one measure per tet: the smaller of its smallest dihedral
// angle over p.guarantee_dihedral_deg and its L_e over its subdomain's median over
// p.guarantee_length_ratio, each goal raised by p.guarantee_margin (so a fixed tet is not left on
// the edge), capped at 1 (good tets do not pull a search); negative for an inverted tet. The
// medians are those of the mesh given to the constructor (or given).
class GuaranteeMeasure {
 public:
  GuaranteeMeasure(const TetMesh& mesh, const PostPassParams& p) : GuaranteeMeasure(median_lengths(mesh), p) {}
  GuaranteeMeasure(std::map<int, double> medians, const PostPassParams& p);
  double operator()(const TetMesh& mesh, const std::array<int, 4>& tet, int group) const;
  double length_ratio(const TetMesh& mesh, const std::array<int, 4>& tet, int group) const;  // L_e / median (< 0: inverted)

 private:
  std::map<int, double> median_;
  double dihedral_goal_, ratio_goal_;
};

}  // namespace tactus::mesher
