// mesher/fibres: the rule-based fibre field of `tactus-mesh fibres` on shapes whose answer is known
// by geometry: a straight "finger" (a 10 x 10 x 60 mm bar along z, based at z = 0) must get the
// bar's axis as its reference direction, and an L-shaped one (up along z, then along x) the
// direction of each arm; everywhere the two families are unit vectors at +-angle to it in the
// plane normal to the skin normal.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "tactus/core/error.hpp"
#include "tactus/core/vec3.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/mesher/fibres.hpp"

using namespace tactus;

namespace {

// Keeps the tets `keep` selects by centroid and tags every boundary face of what is left "skin".
TetMesh with_skin(TetMesh mesh, const std::function<bool(const Vec3&)>& keep) {
  TetMesh out;
  out.nodes = mesh.nodes;
  out.groups = {{3, 1, "soft_tissue"}, {2, 20, "skin"}};
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    Vec3 c{0, 0, 0};
    for (int v : mesh.tets[e])
      for (int d = 0; d < 3; ++d) c[d] += 0.25 * mesh.nodes[static_cast<std::size_t>(v)][d];
    if (keep(c)) out.tets.push_back(mesh.tets[e]), out.tet_group.push_back(1);
  }
  std::map<std::array<int, 3>, std::pair<int, std::array<int, 3>>> faces;
  static const int fv[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  for (const auto& t : out.tets)
    for (const auto& f : fv) {
      std::array<int, 3> tri{t[f[0]], t[f[1]], t[f[2]]}, key = tri;
      std::sort(key.begin(), key.end());
      auto& entry = faces[key];
      ++entry.first, entry.second = tri;
    }
  for (const auto& [key, entry] : faces)
    if (entry.first == 1) out.triangles.push_back(entry.second), out.triangle_group.push_back(20);
  return out;
}

struct Invariants {
  double worst_unit = 0, worst_angle = 0, worst_in_plane = 0, worst_bisector = 0;
};

// |a| = 1, a_1 . a_2 = cos(2 angle), a . n = 0, (a_1 + a_2) along the direction.
Invariants invariants(const mesher::FibreField& f, double angle_deg) {
  Invariants r;
  const double c2 = std::cos(2 * angle_deg * M_PI / 180);
  for (std::size_t e = 0; e < f.fibre_1.size(); ++e) {
    const Vec3 &a = f.fibre_1[e], &b = f.fibre_2[e], &n = f.skin_normal[e], &l = f.direction[e];
    r.worst_unit = std::max({r.worst_unit, std::abs(dot(a, a) - 1), std::abs(dot(b, b) - 1)});
    r.worst_angle = std::max(r.worst_angle, std::abs(dot(a, b) - c2));
    r.worst_in_plane = std::max({r.worst_in_plane, std::abs(dot(a, n)), std::abs(dot(b, n))});
    const Vec3 s = a + b;
    r.worst_bisector = std::max(r.worst_bisector, std::abs(dot(s, l) / std::sqrt(dot(s, s)) - 1));
  }
  return r;
}

void expect_invariants(const mesher::FibreField& f, double angle_deg) {
  const Invariants r = invariants(f, angle_deg);
  std::printf("  invariants: |a| - 1 %.1e, a1.a2 - cos 2theta %.1e, a.n %.1e, bisector %.1e\n", r.worst_unit, r.worst_angle, r.worst_in_plane,
              r.worst_bisector);
  EXPECT_LE(r.worst_unit, 1e-12);
  EXPECT_LE(r.worst_angle, 1e-12);
  EXPECT_LE(r.worst_in_plane, 1e-12);
  EXPECT_LE(r.worst_bisector, 1e-12);
}

Vec3 centroid(const TetMesh& m, std::size_t e) {
  Vec3 c{0, 0, 0};
  for (int v : m.tets[e])
    for (int d = 0; d < 3; ++d) c[d] += 0.25 * m.nodes[static_cast<std::size_t>(v)][d];
  return c;
}

}  // namespace

// Oracle: the bar's axis. Along the bar (away from the base and the rounded-off tip, z in 10..50
// mm) every tet's reference direction is within 3 deg of z.
TEST(Fibres, StraightFingerRunsAlongItsAxis) {
  const TetMesh mesh = with_skin(samples::make_box_mesh(5, 5, 30, 0.01, 0.01, 0.06), [](const Vec3&) { return true; });
  mesher::FibreFieldOptions o;
  o.angle_deg = 30;
  const mesher::FibreField f = mesher::rule_based_fibres(mesh, o);
  double worst = 0;
  std::size_t n = 0;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    const Vec3 c = centroid(mesh, e);
    if (c[2] < 0.01 || c[2] > 0.05) continue;
    worst = std::max(worst, std::acos(std::min(1.0, std::abs(f.direction[e][2]))) * 180 / M_PI), ++n;
  }
  std::printf("straight finger: %zu tets along the bar, largest angle of the reference direction to its axis %.3f deg; base %zu nodes\n", n, worst,
              f.base_nodes);
  EXPECT_LE(worst, 3.0);
  expect_invariants(f, 30);
}

// Oracle: each arm's axis. An L (10 x 10 mm section: up 60 mm along z from the base, then 40 mm
// along +x at the top): in the vertical arm below the bend (z 10..40 mm) the direction is within
// 10 deg of z, in the horizontal arm beyond the bend (x > 25 mm) within 10 deg of x.
TEST(Fibres, BentFingerFollowsTheBend) {
  auto keep = [](const Vec3& c) { return c[0] < 0.01 || c[2] > 0.05; };
  const TetMesh mesh = with_skin(samples::make_box_mesh(25, 5, 30, 0.05, 0.01, 0.06), keep);
  mesher::FibreFieldOptions o;
  o.angle_deg = 20;
  const mesher::FibreField f = mesher::rule_based_fibres(mesh, o);
  double worst_up = 0, worst_across = 0;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    const Vec3 c = centroid(mesh, e);
    const Vec3& l = f.direction[e];
    if (c[0] < 0.01 && c[2] > 0.01 && c[2] < 0.04) worst_up = std::max(worst_up, std::acos(std::min(1.0, std::abs(l[2]))) * 180 / M_PI);
    if (c[0] > 0.025 && c[0] < 0.045) worst_across = std::max(worst_across, std::acos(std::min(1.0, std::abs(l[0]))) * 180 / M_PI);
  }
  std::printf("bent finger: %zu tets; largest angle to z in the vertical arm %.2f deg, to x in the horizontal arm %.2f deg\n", mesh.tets.size(),
              worst_up, worst_across);
  EXPECT_LE(worst_up, 10.0);
  EXPECT_LE(worst_across, 10.0);
  expect_invariants(f, 20);
}

TEST(Fibres, MeshWithoutSkinIsRefused) {
  TetMesh mesh = samples::make_box_mesh(2, 2, 2, 0.01, 0.01, 0.01);
  try {
    mesher::rule_based_fibres(mesh, mesher::FibreFieldOptions{}, "hand.msh");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("hand.msh"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("skin"), std::string::npos) << e.what();
  }
}
