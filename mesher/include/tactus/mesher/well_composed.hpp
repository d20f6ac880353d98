#pragma once
// Label configurations whose boundary cannot be a 2-manifold, found and resolved before meshing,
// and the boundary's topology counted after it.
//
// In a voxel volume a label's boundary is non-manifold where the label touches itself (or another
// part of itself) only along a voxel edge or at a voxel corner: in a 2 x 2 square of voxels the
// two on one diagonal belong to the label and the two on the other do not (an edge pinch), or in a
// 2 x 2 x 2 cube two opposite corners do and the other six do not, or the reverse (a vertex pinch).
// A volume with none of these for any label, nor for the union of all labels (the skin), is
// well-composed (Latecki 2000): every boundary it bounds is a 2-manifold. Each configuration is
// resolved by changing the one voxel of its block whose change removes the most such
// configurations around it without creating others: giving a voxel to the label that makes the
// pair face-connected, or opening the pinch (a voxel of the other side).
#include <array>
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "tactus/core/mesh.hpp"
#include "tactus/core/volume.hpp"

namespace tactus::mesher {

struct WellComposedReport {
  std::size_t edge_pinches = 0, vertex_pinches = 0;  // found before any change (over every label and the skin)
  std::size_t voxels_changed = 0;
  std::size_t remaining = 0;  // configurations left (0 unless the sweeps ran out)
  struct Change {
    std::array<int, 3> voxel{0, 0, 0};
    int from = 0, to = 0;
  };
  std::vector<Change> changes;  // in the order made
};

// The critical configurations of the volume (edge and vertex pinches, every label and the skin).
std::pair<std::size_t, std::size_t> count_critical_configurations(const Volume<std::uint8_t>& labels);

// Resolves them in place (sweeps until none is left, at most 8).
WellComposedReport make_well_composed(Volume<std::uint8_t>& labels);

// The topology of a tet mesh's boundaries: the skin (faces of one tet) and each volume group's own
// boundary (its faces whose other side is another group or nothing). An edge is non-manifold when
// more or fewer than two of the boundary's faces share it; a vertex when its faces on the boundary
// form more than one fan. Faces where three groups meet are each group's own boundary and count
// only there, so a triple junction is not a defect.
struct BoundaryTopology {
  std::size_t faces = 0, non_manifold_edges = 0, non_manifold_vertices = 0;
  Vec3 first_defect{0, 0, 0};  // a defect's position (m), when there is one
};
std::map<std::string, BoundaryTopology> boundary_topology(const TetMesh& mesh);

}  // namespace tactus::mesher
