// mesher/well_composed: label volumes built to have the topologies that give non-manifold mesh
// boundaries (two cubes touching along one edge, two touching at one corner, a label pinched to
// one voxel, a one-voxel sheet between two labels, a shell 1.2 voxels thick). Oracles: the
// critical configurations' definition (counted before, none left after), the boundary's topology
// recounted from the mesh's faces (boundary_topology: each edge in two faces, each vertex one
// fan, for the skin and every group), and the angle guarantee. The shell, thinner than its
// voxels' diagonal, is made well-composed (none left), but CGAL's manifold criterion reaches its
// vertex bound on it and the plain mesh pinches; the mesher's tet pass (boundary_pinches.cpp)
// relabels the tets left pinched (what it moved is printed).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>

#include "mesh_guarantees.hpp"
#include "tactus/mesher/well_composed.hpp"

using namespace tactus;

namespace {

// A 1 mm label volume of n^3 voxels filled by `label(x, y, z)`.
Volume<std::uint8_t> volume_of(int n, const std::function<int(int, int, int)>& label) {
  Volume<std::uint8_t> v({n, n, n}, {1e-3, 1e-3, 1e-3}, {0, 0, 0}, 0);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) v.at(x, y, z) = static_cast<std::uint8_t>(label(x, y, z));
  return v;
}

bool in_box(int x, int y, int z, int x0, int y0, int z0, int x1, int y1, int z1) {
  return x >= x0 && x < x1 && y >= y0 && y < y1 && z >= z0 && z < z1;
}

struct Case {
  const char* name;
  Volume<std::uint8_t> labels;
  LabelTable table;
  std::size_t defects;  // the pinches the volume is built with (0: a thin region, not a pinch)
};

std::vector<Case> cases() {
  const LabelTable tissue{{1, "soft_tissue"}}, tissue_bones{{1, "soft_tissue"}, {2, "bone_02"}, {3, "bone_03"}};
  std::vector<Case> c;
  c.push_back(
      {"two cubes touching along one edge",
       volume_of(24, [](int x, int y, int z) { return in_box(x, y, z, 3, 3, 5, 12, 12, 19) || in_box(x, y, z, 12, 12, 5, 21, 21, 19) ? 1 : 0; }),
       tissue, 14});  // 14 voxel edges along z
  c.push_back(
      {"two cubes touching at one corner",
       volume_of(24, [](int x, int y, int z) { return in_box(x, y, z, 3, 3, 3, 12, 12, 12) || in_box(x, y, z, 12, 12, 12, 21, 21, 21) ? 1 : 0; }),
       tissue, 1});
  c.push_back({"a label pinched to one voxel",
               volume_of(24,
                         [](int x, int y, int z) {
                           return in_box(x, y, z, 2, 6, 6, 11, 18, 18) || in_box(x, y, z, 12, 6, 6, 21, 18, 18) || (x == 11 && y == 12 && z == 12)
                                      ? 1
                                      : 0;
                         }),
               tissue, 0});
  c.push_back({"a one-voxel sheet of tissue between two bones",
               volume_of(24,
                         [](int x, int y, int z) {
                           if (!in_box(x, y, z, 2, 2, 2, 22, 22, 22)) return 0;
                           if (in_box(x, y, z, 5, 5, 5, 11, 19, 19)) return 2;
                           if (in_box(x, y, z, 12, 5, 5, 18, 19, 19)) return 3;
                           return 1;
                         }),
               tissue_bones, 0});
  c.push_back({"a shell 1.2 voxels thick over a bone",
               volume_of(26,
                         [](int x, int y, int z) {
                           const double r = std::sqrt((x - 12.5) * (x - 12.5) + (y - 12.5) * (y - 12.5) + (z - 12.5) * (z - 12.5));
                           return r < 8 ? 2 : r < 9.2 ? 1 : 0;
                         }),
               tissue_bones, 0});
  return c;
}

}  // namespace

TEST(WellComposed, AwkwardTopologiesMeshWithManifoldBoundaries) {
  for (Case& c : cases()) {
    const auto [edges, vertices] = mesher::count_critical_configurations(c.labels);
    Volume<std::uint8_t> fixed = c.labels;
    const mesher::WellComposedReport r = mesher::make_well_composed(fixed);
    const auto [edges_after, vertices_after] = mesher::count_critical_configurations(fixed);
    std::printf("%s: %zu edge and %zu vertex pinch configuration(s); %zu voxel(s) changed (%.1f mm^3 moved), %zu left\n", c.name, edges, vertices,
                r.voxels_changed, static_cast<double>(r.voxels_changed) * fixed.voxel_volume() * 1e9, edges_after + vertices_after);
    EXPECT_EQ(edges_after + vertices_after, 0u) << c.name;
    if (c.defects > 0) {
      EXPECT_GT(edges + vertices, 0u) << c.name;
      EXPECT_LE(r.voxels_changed, 2 * c.defects) << c.name;  // at most two voxels' worth per defect
    }
    const auto [mesh, absorbed] = testkit::mesh_like_tactus_mesh(c.labels, c.table);
    for (const auto& [name, t] : mesher::boundary_topology(mesh)) {
      std::printf("  %s: boundary '%s' %zu faces, %zu non-manifold edges, %zu non-manifold vertices\n", c.name, name.c_str(), t.faces,
                  t.non_manifold_edges, t.non_manifold_vertices);
      EXPECT_EQ(t.non_manifold_edges, 0u) << c.name << ": " << name;
      EXPECT_EQ(t.non_manifold_vertices, 0u) << c.name << ": " << name;
    }
    for (const auto& [label, w] : testkit::recomputed_quality(mesh)) {
      std::printf("  %s, label %d: min dihedral %.2f deg, L_e min/median %.3f\n", c.name, label, w.min_dihedral_deg, w.length_ratio);
      EXPECT_GE(w.min_dihedral_deg, mesher::QualityGuarantees{}.min_dihedral_deg) << c.name;
    }
  }
}
