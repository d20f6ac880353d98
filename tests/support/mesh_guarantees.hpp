#pragma once
// The mesher's guarantees (min dihedral 10 deg, L_e min/median >= 0.2 in every subdomain) checked
// from the node coordinates alone, independently of the mesher's own quality report: dihedral
// angles from the face normals (-grad N_a is the outward normal of the face opposite node a), L_e
// = (sum_a |grad N_a|^2)^(-1/2) from the inverse of the 4x4 coordinate matrix.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <utility>
#include <vector>

#include "tactus/core/mesh.hpp"
#include "tactus/core/volume.hpp"
#include "tactus/mesher/image_mesher.hpp"
#include "tactus/mesher/quality.hpp"
#include "tactus/mesher/small_regions.hpp"
#include "tactus/mesher/thickness.hpp"
#include "tactus/mesher/well_composed.hpp"

namespace tactus::testkit {

struct WorstTet {
  double min_dihedral_deg = 180, length_ratio = 1;
};

// Per volume group: the smallest dihedral angle and the smallest L_e over the group's median.
inline std::map<int, WorstTet> recomputed_quality(const TetMesh& m) {
  std::map<int, std::vector<double>> lengths;
  std::map<int, WorstTet> worst;
  for (std::size_t e = 0; e < m.tets.size(); ++e) {
    Eigen::Matrix4d A;
    for (int a = 0; a < 4; ++a) {
      const Vec3& p = m.nodes[static_cast<std::size_t>(m.tets[e][static_cast<std::size_t>(a)])];
      A.row(a) << 1.0, p[0], p[1], p[2];
    }
    const Eigen::Matrix4d G = A.inverse();  // rows 1..3: the gradients of N_a (columns)
    lengths[m.tet_group[e]].push_back(1.0 / std::sqrt(G.bottomRows(3).squaredNorm()));
    // The dihedral angle at the edge shared by the faces opposite nodes i and j is pi minus the
    // angle between their outward normals.
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const Eigen::Vector3d ni = -G.block<3, 1>(1, i).normalized(), nj = -G.block<3, 1>(1, j).normalized();
        const double angle = 180.0 - std::acos(std::clamp(ni.dot(nj), -1.0, 1.0)) * 180.0 / M_PI;
        worst[m.tet_group[e]].min_dihedral_deg = std::min(worst[m.tet_group[e]].min_dihedral_deg, angle);
      }
  }
  for (auto& [label, v] : lengths) {
    std::sort(v.begin(), v.end());
    worst[label].length_ratio = v.front() / v[v.size() / 2];
  }
  return worst;
}

// Meshes `labels` the way tactus-mesh does with its defaults (small regions absorbed, thin labels
// given a finer size, pinches resolved); returns the mesh and the number of regions absorbed.
inline std::pair<TetMesh, std::size_t> mesh_like_tactus_mesh(Volume<std::uint8_t> labels, const LabelTable& table, mesher::ImageMeshParams p = {}) {
  const auto absorbed = mesher::absorb_small_regions(labels, mesher::min_region_voxels(labels, 0, p.bone_cell_size_mm));
  mesher::fit_thin_labels(labels, table, p, 0, "labels");
  mesher::make_well_composed(labels);
  return {mesher::mesh_label_volume(labels, table, p), absorbed.size()};
}

// Prints each group's numbers against the mesher's guarantees (QualityGuarantees) and expects
// them met, and the mesher's quality report to say so. `length_ratio_floor` below the guarantee's
// L_e ratio is for a scan whose mesh may hold the known unfixed sliver class (design.md, the
// mesher's post-passes: a soft-tissue tet flat on a bone with all four nodes on its surfaces, where
// no flip is valid); the report's "met" is then not required, and the floor still bounds how far
// below the guarantee it may be.
inline void expect_mesh_guarantees(const char* name, const TetMesh& mesh, double length_ratio_floor = mesher::QualityGuarantees{}.min_length_ratio) {
  const mesher::QualityGuarantees guarantee;
  for (const auto& [label, w] : recomputed_quality(mesh)) {
    std::printf("  %s, label %d: min dihedral %.2f deg (>= %.0f), L_e min/median %.3f (>= %.2f)\n", name, label, w.min_dihedral_deg,
                guarantee.min_dihedral_deg, w.length_ratio, length_ratio_floor);
    EXPECT_GE(w.min_dihedral_deg, guarantee.min_dihedral_deg) << name << " label " << label;
    EXPECT_GE(w.length_ratio, length_ratio_floor) << name << " label " << label;
  }
  const auto report = mesher::quality_report(mesh, {});
  if (length_ratio_floor >= guarantee.min_length_ratio) {
    EXPECT_TRUE(report["guarantees"]["met"].get<bool>()) << report["guarantees"].dump(1);
  } else {
    std::printf("  %s: mesher's report says the guarantees are %s\n", name, report["guarantees"]["met"].get<bool>() ? "met" : "not met");
  }
}

}  // namespace tactus::testkit
