#pragma once
#include <array>
#include <map>
// A conforming multi-material tetrahedral mesh of a label volume with CGAL's 3-D mesher
// (labelled-image domain, paper §3.1: one continuous mesh of bones and soft tissue "without
// interfaces"): one subdomain per label, nodes shared across every interface.
#include <string>

#include "tactus/core/contracts.hpp"
#include "tactus/core/mesh.hpp"
#include "tactus/core/volume.hpp"
#include "tactus/mesher/post_passes.hpp"

namespace tactus::mesher {

struct ImageMeshParams {
  double facet_angle_deg = 25;      // lower bound on surface triangle angles, (0, 30]
  double facet_size_mm = 4.0;       // upper bound on surface triangle circumradius (skin)
  double bone_facet_size_mm = 3.0;  // the same on the bone / soft-tissue interfaces
  double facet_distance_mm = 0.6;   // surface approximation error bound
  // Gaussian sigma, in voxels, of the label indicators that place the boundaries (0: each point
  // takes its nearest voxel's label, and surfaces follow the voxels' staircase; see image_mesher.cpp).
  double boundary_smoothing_voxels = 0;
  // A refined region (e.g. where the skin will touch): inside the world box refine_box_m (x0, y0,
  // z0, x1, y1, z1, m) the facet size is at most refine_size_mm, the cell size at most
  // refine_cell_size_mm (0: the cell sizes outside; tactus-mesh passes twice the facet size, the
  // cells grading inward from the finer surface) and the facet distance at most refine_distance_mm
  // (0: the facet distance outside). Off while refine_size_mm is 0.
  std::array<double, 6> refine_box_m{};
  double refine_size_mm = 0;
  double refine_cell_size_mm = 0;
  double refine_distance_mm = 0;
  // Also refined (with refine_size_mm): every voxel within refine_joints_mm of two different bones
  // along each axis - a joint's gap, the tissue of its crease and the skin over it, where a
  // flexing joint squeezes one layer of tets (0: off; docs/studies/grasp.md).
  double refine_joints_mm = 0;
  double cell_radius_edge = 3.0;   // upper bound on circumradius / shortest edge, >= 2
  double cell_size_mm = 7.0;       // soft tissue cell circumradius bound
  double bone_cell_size_mm = 3.5;  // the same in bones (finer)
  // Per label, a cell and facet size of its own (mm) in place of the two above: a label thinner
  // than its cells (thickness.hpp) gets a few elements across it.
  std::map<int, double> label_cell_size_mm;
  bool odt = false, lloyd = false;  // global optimisers (slow); perturb + exude are on by default
  bool perturb = true, exude = true;
  double exude_sliver_bound_deg = 12;  // exudation targets dihedral angles below this
  double optimiser_time_limit_s = 30;
  int relocate_passes = 6;               // node relocation of the tets that set the stable step (0: off)
  PostPassParams post;                   // the post-passes' thresholds (post_passes.hpp)
  bool restore_volumes = true;           // offset surfaces to the label volumes (see image_mesher.cpp)
  bool peel_skin_slivers = true;         // remove soft-tissue slivers lying flat on the skin (see image_mesher.cpp)
  bool resolve_boundary_pinches = true;  // relabel or remove tets at non-manifold boundary edges and vertices (boundary_pinches.cpp)
  unsigned seed = 0;
  double max_elements = 1e7;  // refused above this many expected tets (a runaway guard; raise it knowingly)
};

// The number of tets CGAL's cell-size criterion is expected to give for these labels, from each
// subdomain's volume and cell size (tets average about a tenth of their circumradius cubed).
// The voxels within `mm` (along each axis) of two different bone labels, one byte per voxel of
// `labels` (empty when mm is 0): the joints' region refine_joints_mm refines.
std::vector<std::uint8_t> joint_gap_mask(const Volume<std::uint8_t>& labels, double mm);
double expected_tets(const Volume<std::uint8_t>& labels, const ImageMeshParams& params);

// Physical groups written: volumes by label (1 "soft_tissue", 2.. the label table's names, e.g.
// "bone_02"), surfaces 1001 "skin" (soft tissue / outside) and 1002 "bone_interface".
constexpr int kSkinTag = contracts::kSkinTag, kBoneInterfaceTag = contracts::kBoneInterfaceTag;

// What the meshing did that quality.json reports: whether CGAL's manifold criterion reached its
// vertex bound (the mesh then made without it), and what the tet-level pinch pass changed.
struct ImageMeshReport {
  bool manifold_criterion_capped = false;
  BoundaryPinchReport pinches;
};

TetMesh mesh_label_volume(const Volume<std::uint8_t>& labels, const LabelTable& table, const ImageMeshParams& params,
                          ImageMeshReport* report = nullptr);

}  // namespace tactus::mesher
