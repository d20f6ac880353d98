#pragma once
// Face keys, the faces of a tet, and the guarantee measure, for the post-passes.
#include <array>
#include <map>

#include "tactus/core/mesh.hpp"
#include "tactus/mesher/post_passes.hpp"

namespace tactus::mesher {

std::array<int, 3> sorted_face(int a, int b, int c);
inline constexpr int kFaces[4][4] = {{1, 2, 3, 0}, {0, 2, 3, 1}, {0, 1, 3, 2}, {0, 1, 2, 3}};  // face nodes, then the opposite

// The guarantees (PostPassParams) as one measure per tet: the smaller of its smallest dihedral
// angle over p.guarantee_dihedral_deg and its L_e over its subdomain's median over
// p.guarantee_length_ratio, each goal raised by p.guarantee_margin (so a fixed tet is not left on
// the edge), capped at 1 (good tets do not pull a search); negative for an inverted tet. The
// medians are those of the mesh given to the constructor.
class GuaranteeMeasure {
 public:
  GuaranteeMeasure(const TetMesh& mesh, const PostPassParams& p);
  double operator()(const TetMesh& mesh, const std::array<int, 4>& tet, int group) const;
  double length_ratio(const TetMesh& mesh, const std::array<int, 4>& tet, int group) const;  // L_e / median (< 0: inverted)

 private:
  std::map<int, double> median_;
  double dihedral_goal_, ratio_goal_;
};

}  // namespace tactus::mesher
