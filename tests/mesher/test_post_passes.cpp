// The mesher's post-passes on hand-made meshes (no CGAL): boundary triangles rebuilt from the
// labels, volume restore, node relocation, skin-sliver peeling and boundary pinches. Oracles:
// exact volumes and areas of boxes, the characteristic length of a regular Kuhn cell, and counts
// of tets and faces (boundary_topology's non-manifold edges and vertices).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <set>

#include "tactus/core/contracts.hpp"
#include "tactus/core/stable_step.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/mesher/post_passes.hpp"
#include "tactus/mesher/well_composed.hpp"

using namespace tactus;
using namespace tactus::mesher;

namespace {

constexpr double kCell = 1e-3;  // 1 mm Kuhn cells

// An n x n x n box of soft tissue (label 1) with its skin rebuilt from the labels.
TetMesh soft_box(int n) {
  TetMesh mesh = samples::make_box_mesh(n, n, n, n * kCell, n * kCell, n * kCell);
  std::fill(mesh.tet_group.begin(), mesh.tet_group.end(), contracts::kSoftTissueLabel);
  rebuild_boundary_triangles(mesh);
  return mesh;
}

double mesh_volume(const TetMesh& m) {
  double v = 0;
  for (const auto& t : m.tets)
    v += tet_volume(m.nodes[static_cast<std::size_t>(t[0])], m.nodes[static_cast<std::size_t>(t[1])], m.nodes[static_cast<std::size_t>(t[2])],
                    m.nodes[static_cast<std::size_t>(t[3])]);
  return v;
}

double min_volume(const TetMesh& m) {
  double v = 1e300;
  for (const auto& t : m.tets)
    v = std::min(v, tet_volume(m.nodes[static_cast<std::size_t>(t[0])], m.nodes[static_cast<std::size_t>(t[1])],
                               m.nodes[static_cast<std::size_t>(t[2])], m.nodes[static_cast<std::size_t>(t[3])]));
  return v;
}

double length(const TetMesh& m, std::size_t e) {
  const auto& t = m.tets[e];
  const auto g = tet_shape_gradients(m.nodes[static_cast<std::size_t>(t[0])], m.nodes[static_cast<std::size_t>(t[1])],
                                     m.nodes[static_cast<std::size_t>(t[2])], m.nodes[static_cast<std::size_t>(t[3])]);
  return g.volume > 0 ? characteristic_length(g) : 0.0;
}

double shortest_length(const TetMesh& m) {
  double l = 1e300;
  for (std::size_t e = 0; e < m.tets.size(); ++e) l = std::min(l, length(m, e));
  return l;
}

std::size_t node_at(const TetMesh& m, double x, double y, double z) {
  for (std::size_t k = 0; k < m.nodes.size(); ++k)
    if (std::abs(m.nodes[k][0] - x) < 1e-12 && std::abs(m.nodes[k][1] - y) < 1e-12 && std::abs(m.nodes[k][2] - z) < 1e-12) return k;
  ADD_FAILURE() << "no node at " << x << " " << y << " " << z;
  return 0;
}

// Sum over the triangles of area-normal . centroid = 3 x enclosed volume (divergence theorem),
// positive when every triangle faces outward.
double enclosed_volume(const TetMesh& m, int group) {
  double v = 0;
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    if (m.triangle_group[t] != group) continue;
    const auto n = area_normal(m, m.triangles[t]);
    Vec3 c{0, 0, 0};
    for (int k : m.triangles[t])
      for (std::size_t i = 0; i < 3; ++i) c[i] += m.nodes[static_cast<std::size_t>(k)][i] / 3;
    v += (n[0] * c[0] + n[1] * c[1] + n[2] * c[2]) / 3;
  }
  return v;
}

}  // namespace

// A 2x2x2 box: 6 faces x 4 cells x 2 triangles of skin, facing out (they enclose +8 mm^3); with
// the upper half labelled as a bone, the 8 interface triangles face out of the bone.
TEST(PostPasses, BoundaryTrianglesFromLabels) {
  TetMesh mesh = soft_box(2);
  EXPECT_EQ(mesh.triangles.size(), 48u);
  const double v = 8 * kCell * kCell * kCell;
  std::cout << "skin encloses " << enclosed_volume(mesh, contracts::kSkinTag) << " m^3 (box " << v << ")\n";
  EXPECT_NEAR(enclosed_volume(mesh, contracts::kSkinTag), v, 1e-12 * v);

  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    double zc = 0;
    for (int k : mesh.tets[e]) zc += mesh.nodes[static_cast<std::size_t>(k)][2] / 4;
    if (zc > kCell) mesh.tet_group[e] = contracts::kFirstBoneLabel;
  }
  rebuild_boundary_triangles(mesh);
  const auto interfaces = std::count(mesh.triangle_group.begin(), mesh.triangle_group.end(), contracts::kBoneInterfaceTag);
  EXPECT_EQ(interfaces, 8);
  // Every interface triangle lies in z = 1 mm and faces down, out of the bone above it.
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (mesh.triangle_group[t] != contracts::kBoneInterfaceTag) continue;
    for (int k : mesh.triangles[t]) EXPECT_NEAR(mesh.nodes[static_cast<std::size_t>(k)][2], kCell, 1e-15);
    EXPECT_LT(area_normal(mesh, mesh.triangles[t])[2], 0);
  }
}

// A 4 mm box mesh whose label volume is a 4.2 mm box (13.6 % short): one offset along the vertex
// normals brings the mesh volume within 1.5 % of the label volume. (Not exactly: along the box's
// edges and at its corners the vertex normals are diagonal, so those nodes move by less than the
// offset in each face's direction; on the mesher's smooth surfaces this error is far smaller.)
TEST(PostPasses, VolumeRestoreReachesTheLabelVolume) {
  TetMesh mesh = soft_box(4);
  const int n = 42;  // 0.1 mm voxels
  Volume<std::uint8_t> labels({n, n, n}, {1e-4, 1e-4, 1e-4}, {0, 0, 0}, contracts::kSoftTissueLabel);
  const double goal = labels.voxel_volume() * n * n * n;
  const double before = mesh_volume(mesh);
  restore_volumes(mesh, labels, std::vector<int>(mesh.triangles.size(), 0));
  const double after = mesh_volume(mesh);
  std::cout << "label volume " << goal << ", mesh before " << before << " (" << (before / goal - 1) * 100 << " %), after " << after << " ("
            << (after / goal - 1) * 100 << " %)\n";
  EXPECT_GT(std::abs(before / goal - 1), 0.13);
  EXPECT_LT(std::abs(after / goal - 1), 0.015);
  EXPECT_GT(min_volume(mesh), 0);
}

// A label volume far smaller than the mesh asks for an offset that would invert tets: it is
// halved until no tet inverts, and the mesh never holds an inverted tet.
TEST(PostPasses, VolumeRestoreNeverInverts) {
  TetMesh mesh = soft_box(2);
  Volume<std::uint8_t> labels({2, 2, 2}, {1e-4, 1e-4, 1e-4}, {0, 0, 0}, contracts::kSoftTissueLabel);
  const double before = mesh_volume(mesh);
  restore_volumes(mesh, labels, std::vector<int>(mesh.triangles.size(), 0));
  std::cout << "volume " << before << " -> " << mesh_volume(mesh) << ", smallest tet " << min_volume(mesh) << "\n";
  EXPECT_GT(min_volume(mesh), 0);
  EXPECT_LT(mesh_volume(mesh), before);  // it still moved inward, by a halved offset
}

// An interior node pushed 0.8 mm towards its neighbour below flattens the tets around it; the
// relocation moves it back until no tet is shorter than the goal fraction of the median.
TEST(PostPasses, RelocationFixesShortInteriorTets) {
  TetMesh mesh = soft_box(3);
  const std::size_t k = node_at(mesh, kCell, kCell, kCell);
  mesh.nodes[k][2] -= 0.8 * kCell;
  const double regular = length(soft_box(3), 0);
  const double before = shortest_length(mesh);
  PostPassParams p;
  relocate_short_tets(mesh, 0.1 * kCell, p);
  const double after = shortest_length(mesh);
  std::cout << "shortest L_e / regular cell's: before " << before / regular << ", after " << after / regular << " (goal " << p.relocate_ratio_goal
            << ")\n";
  EXPECT_LT(before / regular, p.relocate_ratio_goal);
  EXPECT_GE(after / regular, p.relocate_ratio_goal);
  EXPECT_GT(min_volume(mesh), 0);
}

// A skin node pushed along the surface is moved in its tangent plane only (it stays on z = 0)
// and by at most the allowed distance.
TEST(PostPasses, RelocationKeepsSurfaceNodesOnTheSurface) {
  TetMesh mesh = soft_box(3);
  const std::size_t k = node_at(mesh, kCell, kCell, 0);
  mesh.nodes[k][0] += 0.85 * kCell;
  const Vec3 start = mesh.nodes[k];
  const double before = shortest_length(mesh);
  const double max_move = 0.3 * kCell;
  relocate_short_tets(mesh, max_move);
  const double moved = std::hypot(mesh.nodes[k][0] - start[0], mesh.nodes[k][1] - start[1]);
  std::cout << "surface node moved " << moved * 1e3 << " mm (at most " << max_move * 1e3 << "), z " << mesh.nodes[k][2] << ", shortest L_e " << before
            << " -> " << shortest_length(mesh) << "\n";
  EXPECT_EQ(mesh.nodes[k][2], 0.0);
  EXPECT_GT(moved, 0);
  EXPECT_LE(moved, max_move * (1 + 1e-12));
  EXPECT_GT(shortest_length(mesh), before);
}

// Two flat tets on top of the box, over the two skin triangles of one top cell, sharing a node
// 0.02 mm above the middle of the cell's diagonal: slivers of the skin. One is peeled; the other
// stays, because peeling it too would leave the shared node without a tet (every node is kept).
TEST(PostPasses, PeelingRemovesASkinSliverButKeepsEveryNode) {
  TetMesh mesh = soft_box(2);
  const std::size_t tets = mesh.tets.size();
  std::vector<std::array<int, 3>> top;  // the two skin triangles of the top cell at x, y < 1 mm
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    bool in_cell = true;
    for (int k : mesh.triangles[t]) {
      const auto& x = mesh.nodes[static_cast<std::size_t>(k)];
      in_cell = in_cell && x[2] > 2 * kCell - 1e-12 && x[0] < kCell + 1e-12 && x[1] < kCell + 1e-12;
    }
    if (in_cell) top.push_back(mesh.triangles[t]);
  }
  ASSERT_EQ(top.size(), 2u);
  Vec3 apex{0, 0, 0};  // above the middle of the shared diagonal
  for (int k : top[0])
    if (std::count(top[1].begin(), top[1].end(), k))
      for (std::size_t i = 0; i < 3; ++i) apex[i] += mesh.nodes[static_cast<std::size_t>(k)][i] / 2;
  apex[2] += 0.02 * kCell;
  mesh.nodes.push_back(apex);
  const int a = static_cast<int>(mesh.nodes.size()) - 1;
  for (const auto& f : top) {
    mesh.tets.push_back({f[0], f[1], f[2], a});
    const auto& t = mesh.tets.back();
    if (tet_volume(mesh.nodes[static_cast<std::size_t>(t[0])], mesh.nodes[static_cast<std::size_t>(t[1])], mesh.nodes[static_cast<std::size_t>(t[2])],
                   mesh.nodes[static_cast<std::size_t>(t[3])]) < 0)
      std::swap(mesh.tets.back()[1], mesh.tets.back()[2]);
    mesh.tet_group.push_back(contracts::kSoftTissueLabel);
  }
  rebuild_boundary_triangles(mesh);
  ASSERT_GT(min_volume(mesh), 0);
  ASSERT_EQ(mesh.triangles.size(), 50u);  // the slivers' four outer faces cover two triangles

  const double box = 8 * std::pow(kCell, 3);
  const std::size_t removed = peel_skin_slivers(mesh);
  const double kept = mesh_volume(mesh) - box;
  std::cout << "peeled " << removed << " tet(s), " << mesh.tets.size() << " left, " << mesh.triangles.size() << " skin triangles, sliver volume kept "
            << kept << " m^3\n";
  EXPECT_EQ(removed, 1u);
  EXPECT_EQ(mesh.tets.size(), tets + 1);
  EXPECT_EQ(mesh.triangles.size(), 50u);  // the kept sliver's three outer faces instead of its base
  EXPECT_GT(kept, 0);
  EXPECT_NEAR(enclosed_volume(mesh, contracts::kSkinTag), box + kept, 1e-12 * box);
}

// Nothing to peel on a regular box: no tet is short.
TEST(PostPasses, PeelingLeavesARegularMeshAlone) {
  TetMesh mesh = soft_box(2);
  EXPECT_EQ(peel_skin_slivers(mesh), 0u);
  EXPECT_EQ(mesh.tets.size(), 48u);
}

// A flat soft-tissue tet (a, b, c, q), q 0.05 mm above the middle of an equilateral 1 mm face
// (a, b, c), on a good tet (a, b, c, p) with p 0.8 mm below: relocation cannot lift q if it lies
// on a surface, but a 2-3 flip makes three tets around the new edge pq. Nine unit tets of soft
// tissue elsewhere set the subdomain's median L_e. Oracles: the pair's volume (kept exactly), the
// three tets' orientation, the worst L_e over the median before and after; and across an
// interface (the lower tet bone) nothing may flip.
TEST(PostPasses, FaceFlipLiftsAFlatTetAndKeepsInterfaces) {
  const auto make = [](int lower_group) {
    TetMesh mesh;
    const double h = std::sqrt(3.0) / 2;
    mesh.nodes = {{0, 0, 0},
                  {kCell, 0, 0},
                  {0.5 * kCell, h * kCell, 0},
                  {0.5 * kCell, h / 3 * kCell, 0.05 * kCell},
                  {0.5 * kCell, h / 3 * kCell, -0.8 * kCell}};
    mesh.tets = {{0, 1, 2, 3}, {0, 2, 1, 4}};
    mesh.tet_group = {contracts::kSoftTissueLabel, lower_group};
    for (int k = 0; k < 9; ++k) {  // regular unit tets, apart from the pair and each other
      const int n = static_cast<int>(mesh.nodes.size());
      const double x = 5 * kCell * (k + 1), s = kCell;
      mesh.nodes.push_back({x, 0, 0}), mesh.nodes.push_back({x + s, 0, 0}), mesh.nodes.push_back({x + s / 2, h * s, 0});
      mesh.nodes.push_back({x + s / 2, h / 3 * s, std::sqrt(2.0 / 3.0) * s});
      mesh.tets.push_back({n, n + 1, n + 2, n + 3});
      mesh.tet_group.push_back(contracts::kSoftTissueLabel);
    }
    rebuild_boundary_triangles(mesh);
    return mesh;
  };
  TetMesh mesh = make(contracts::kSoftTissueLabel);
  ASSERT_GT(min_volume(mesh), 0);
  const double regular = length(mesh, 2), volume = mesh_volume(mesh), before = shortest_length(mesh) / regular;
  const std::size_t tets = mesh.tets.size();
  const std::size_t flipped = flip_poor_tets(mesh);
  const double after = shortest_length(mesh) / regular;
  std::cout << "face flip: " << flipped << " flip(s), " << tets << " -> " << mesh.tets.size() << " tets; worst L_e / median " << before << " -> "
            << after << " (guarantee 0.2); volume " << volume << " -> " << mesh_volume(mesh) << " m^3\n";
  EXPECT_EQ(flipped, 1u);
  EXPECT_EQ(mesh.tets.size(), tets + 1);
  EXPECT_LT(before, 0.2);
  EXPECT_GE(after, 0.2 * 1.1);
  EXPECT_GT(min_volume(mesh), 0);
  EXPECT_NEAR(mesh_volume(mesh), volume, 1e-12 * volume);

  TetMesh across = make(contracts::kFirstBoneLabel);
  const std::size_t interface_flips = flip_poor_tets(across);
  std::cout << "face flip across a tissue-bone interface: " << interface_flips << " flip(s)\n";
  EXPECT_EQ(interface_flips, 0u);
  EXPECT_EQ(across.tets.size(), tets);
}

// A sliver (p0, p1, p2, p3): the diagonals of a unit square, p0 p1 0.05 mm above p2 p3, crossing,
// under a tip 1.5 mm up joined to both faces above p0 p1: three tets around the edge p0 p1 (every
// face flip would make an edge that exists). Edge removal (a 3-2 flip) leaves two tets around the
// upright triangle (p2, p3, tip), one on each side. Oracles as above: the volume kept, positive
// tets, the worst L_e over the median before and after, one tet fewer.
TEST(PostPasses, EdgeRemovalTakesOutASliver) {
  TetMesh mesh;
  const double d = 0.05 * kCell, h = std::sqrt(3.0) / 2;
  mesh.nodes = {{-kCell, 0, d}, {kCell, 0, d}, {0, -kCell, -d}, {0, kCell, -d}, {0, 0, 1.5 * kCell}};
  mesh.tets = {{0, 1, 2, 3}, {0, 1, 3, 4}, {0, 1, 4, 2}};
  for (auto& t : mesh.tets) {
    const auto x = [&](int v) { return mesh.nodes[static_cast<std::size_t>(v)]; };
    if (tet_volume(x(t[0]), x(t[1]), x(t[2]), x(t[3])) < 0) std::swap(t[2], t[3]);
  }
  mesh.tet_group.assign(3, contracts::kSoftTissueLabel);
  for (int k = 0; k < 9; ++k) {  // regular 1.4 mm tets elsewhere: the subdomain's median L_e
    const int n = static_cast<int>(mesh.nodes.size());
    const double x = 5 * kCell * (k + 1), s = 1.4 * kCell;
    mesh.nodes.push_back({x, 0, 0}), mesh.nodes.push_back({x + s, 0, 0}), mesh.nodes.push_back({x + s / 2, h * s, 0});
    mesh.nodes.push_back({x + s / 2, h / 3 * s, std::sqrt(2.0 / 3.0) * s});
    mesh.tets.push_back({n, n + 1, n + 2, n + 3});
    mesh.tet_group.push_back(contracts::kSoftTissueLabel);
  }
  rebuild_boundary_triangles(mesh);
  ASSERT_GT(min_volume(mesh), 0);
  const double regular = length(mesh, 3), volume = mesh_volume(mesh), before = shortest_length(mesh) / regular;
  const std::size_t tets = mesh.tets.size(), triangles = mesh.triangles.size();
  const std::size_t flipped = flip_poor_tets(mesh);
  const double after = shortest_length(mesh) / regular;
  rebuild_boundary_triangles(mesh);
  std::cout << "edge removal: " << flipped << " flip(s), " << tets << " -> " << mesh.tets.size() << " tets; worst L_e / median " << before << " -> "
            << after << " (guarantee 0.2); volume " << volume << " -> " << mesh_volume(mesh) << " m^3; " << triangles << " -> "
            << mesh.triangles.size() << " boundary triangles\n";
  EXPECT_EQ(flipped, 1u);
  EXPECT_EQ(mesh.tets.size(), tets - 1);
  EXPECT_LT(before, 0.2);
  EXPECT_GE(after, 0.2 * 1.1);
  EXPECT_GT(min_volume(mesh), 0);
  EXPECT_NEAR(mesh_volume(mesh), volume, 1e-12 * volume);
  EXPECT_EQ(mesh.triangles.size(), triangles);  // the outer faces stay
}

namespace {

// The cell (i, j) of a box mesh's layer that a tet's centroid lies in (1 mm cells).
std::pair<int, int> cell_of(const TetMesh& mesh, std::size_t e) {
  double x = 0, y = 0;
  for (int k : mesh.tets[e]) x += mesh.nodes[static_cast<std::size_t>(k)][0] / 4, y += mesh.nodes[static_cast<std::size_t>(k)][1] / 4;
  return {static_cast<int>(x / kCell), static_cast<int>(y / kCell)};
}

std::size_t all_defects(const TetMesh& mesh) {
  std::size_t n = 0;
  for (const auto& [name, t] : boundary_topology(mesh)) n += t.non_manifold_edges + t.non_manifold_vertices;
  return n;
}

double group_volume(const TetMesh& m, int group) {
  double v = 0;
  for (std::size_t e = 0; e < m.tets.size(); ++e)
    if (m.tet_group[e] == group) {
      const auto& t = m.tets[e];
      v += tet_volume(m.nodes[static_cast<std::size_t>(t[0])], m.nodes[static_cast<std::size_t>(t[1])], m.nodes[static_cast<std::size_t>(t[2])],
                      m.nodes[static_cast<std::size_t>(t[3])]);
    }
  return v;
}

}  // namespace

// Two bone cells touching along one edge in a 2 x 2 x 1 box of tissue (the cells on a diagonal
// bone, the others tissue): the bone's own boundary has four faces on the shared edge, and its
// ends are non-manifold vertices. The pinch pass relabels tets of the smallest run around each
// defect. Oracles: boundary_topology's count, 0 after; the body's volume (the skin) exactly kept;
// the bone volume moved at most one cell's (1 mm^3) - a tet is a sixth of a cell.
TEST(PostPasses, PinchPassMakesTwoCellsTouchingAlongAnEdgeManifold) {
  TetMesh mesh = samples::make_box_mesh(2, 2, 1, 2 * kCell, 2 * kCell, kCell);
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    const auto [i, j] = cell_of(mesh, e);
    mesh.tet_group[e] = i == j ? contracts::kFirstBoneLabel : contracts::kSoftTissueLabel;
  }
  rebuild_boundary_triangles(mesh);
  const double volume = mesh_volume(mesh), bone = group_volume(mesh, contracts::kFirstBoneLabel);
  const std::size_t before = all_defects(mesh);
  const BoundaryPinchReport r = resolve_boundary_pinches(mesh);
  const double moved = std::abs(group_volume(mesh, contracts::kFirstBoneLabel) - bone);
  std::cout << "edge-touching cells: " << before << " defects (boundary_topology) -> " << all_defects(mesh) << "; the pass counted "
            << r.defects_before << " -> " << r.defects_after << ", relabelled " << r.tets_relabelled << " tets (" << r.volume_moved_m3 * 1e9
            << " mm^3, bone volume changed by " << moved * 1e9 << " mm^3 of a 1 mm^3 cell)\n";
  EXPECT_GT(before, 0u);
  EXPECT_EQ(r.defects_before, before);
  EXPECT_EQ(all_defects(mesh), 0u);
  EXPECT_EQ(r.defects_after, 0u);
  EXPECT_EQ(r.tets_removed, 0u);
  EXPECT_NEAR(mesh_volume(mesh), volume, 1e-12 * volume);
  EXPECT_GT(moved, 0);
  EXPECT_LE(r.volume_moved_m3, kCell * kCell * kCell * (1 + 1e-12));
}

// The body itself pinched: two cells of a 2 x 2 x 1 box touching along an edge, the other two
// empty. The skin is non-manifold on that edge; only removing tets can open it (nothing can be
// added outside). Oracles: 0 defects after, every node still in a tet, at most one cell's volume
// removed, both cells still there.
TEST(PostPasses, PinchPassOpensABodyTouchingItselfAlongAnEdge) {
  TetMesh box = samples::make_box_mesh(2, 2, 1, 2 * kCell, 2 * kCell, kCell);
  TetMesh mesh = box;
  mesh.tets.clear(), mesh.tet_group.clear();
  for (std::size_t e = 0; e < box.tets.size(); ++e)
    if (const auto [i, j] = cell_of(box, e); i == j) mesh.tets.push_back(box.tets[e]), mesh.tet_group.push_back(contracts::kSoftTissueLabel);
  rebuild_boundary_triangles(mesh);
  const double volume = mesh_volume(mesh);
  const std::size_t before = all_defects(mesh);
  const BoundaryPinchReport r = resolve_boundary_pinches(mesh);
  std::set<int> used;
  for (const auto& t : mesh.tets) used.insert(t.begin(), t.end());
  std::cout << "edge-touching body: " << before << " defects -> " << all_defects(mesh) << "; removed " << r.tets_removed << " tets ("
            << (volume - mesh_volume(mesh)) * 1e9 << " mm^3 of 2 mm^3)\n";
  EXPECT_GT(before, 0u);
  EXPECT_EQ(all_defects(mesh), 0u);
  EXPECT_GT(r.tets_removed, 0u);
  EXPECT_EQ(used.size(), 14u);  // the two cells' 2 x 8 corners less the two on the shared edge
  EXPECT_NEAR(volume - mesh_volume(mesh), r.volume_moved_m3, 1e-12 * volume);
  EXPECT_LE(volume - mesh_volume(mesh), kCell * kCell * kCell * (1 + 1e-12));
}
