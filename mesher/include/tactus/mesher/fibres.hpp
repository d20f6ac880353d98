#pragma once
// Rule-based fibre fields for the hgo soft tissue (`tactus-mesh fibres`), in the spirit of the
// Laplace-Dirichlet rule-based fields used for cardiac fibres (Bayer et al. 2012): a potential
// solved on the mesh gives, per tet, a smooth reference direction along the hand; the normal of
// the nearest skin triangle gives the local skin plane; the two fibre families lie at +-angle to
// the reference direction in that plane.
//   longitudinal: -lap(phi) = 1 with phi = 0 on the base cut (the nodes within base_fraction of the
//                 mesh's extent along `axis`, the wrist): phi grows away from the base along every
//                 branch, so grad(phi) runs along the forearm, the palm and each finger to its tip
//                 (a plain Laplace problem would need a Dirichlet value at every fingertip).
//   skin plane:   n, the unit normal of the skin triangle nearest to the tet's centroid (a skin
//                 potential's gradient was tried first: it vanishes on the medial axis of a
//                 finger, where its direction is noise).
// Per tet: e_l = grad(phi) - (grad(phi).n) n normalised (where grad(phi) is along n, at a fingertip,
// the axis projected instead), e_c = n x e_l, a_1,2 = cos(angle) e_l +- sin(angle) e_c.
#include <string>
#include <vector>

#include "tactus/core/mesh.hpp"

namespace tactus::mesher {

struct FibreFieldOptions {
  double angle_deg = 30;        // each family's angle to the reference direction
  int axis = 2;                 // 0, 1, 2: the axis whose low end is the base (the phantom's wrist: z)
  double base_fraction = 0.03;  // nodes within this fraction of the extent from the low end: phi = 0
  std::string skin_group = "skin";
};

struct FibreField {
  std::vector<Vec3> fibre_1, fibre_2;  // per tet: the two unit fibre directions
  std::vector<Vec3> direction;         // per tet: the reference direction e_l
  std::vector<Vec3> skin_normal;       // per tet: the unit normal of the nearest skin triangle
  std::vector<double> skin_distance;   // per tet: its centroid's distance to the skin, m
  std::vector<double> phi;             // per node: the longitudinal potential
  std::size_t base_nodes = 0, skin_nodes = 0;
};

// Throws InputError naming `source` when the skin group is missing or the base selects no node.
FibreField rule_based_fibres(const TetMesh& mesh, const FibreFieldOptions& options, const std::string& source = "mesh");

}  // namespace tactus::mesher
