// core/skeleton: forward kinematics against the closed form, and the file's round trip and checks.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/skeleton.hpp"
#include "temp_dir.hpp"

using namespace tactus;
using tactus::testkit::TempDir;

namespace {
// A planar 3-bone chain along x from the origin, a root "base" of length l0 and two links of
// lengths l1, l2, palm normal -y: the flexion axis is d x n = x x (-y) = -z, and a positive
// flexion turns the chain towards -y.
Skeleton planar_chain(double l0, double l1, double l2) {
  Skeleton sk;
  sk.source = "test";
  sk.palm_normal = {0, -1, 0};
  sk.bones = {{"base", "", 2, {l0 / 2, 0, 0}, {1, 0, 0}, l0},
              {"link1", "base", 3, {l0 + l1 / 2, 0, 0}, {1, 0, 0}, l1},
              {"tip", "link1", 4, {l0 + l1 + l2 / 2, 0, 0}, {1, 0, 0}, l2}};
  sk.joints = {{"j1", "base", "link1", {l0, 0, 0}, {0, 0, -1}, {0, -1, 0}}, {"j2", "link1", "tip", {l0 + l1, 0, 0}, {0, 0, -1}, {0, -1, 0}}};
  return sk;
}
}  // namespace

// Oracle: the closed form of a planar two-link chain: the tip of the last link at
// (l0 + l1 cos t1 + l2 cos(t1 + t2), -(l1 sin t1 + l2 sin(t1 + t2))).
TEST(Skeleton, ForwardKinematicsOfAChainIsExact) {
  const double l0 = 0.05, l1 = 0.04, l2 = 0.025, t1 = 0.7, t2 = 0.45;
  const Skeleton sk = planar_chain(l0, l1, l2);
  validate_skeleton(sk, "test");
  const auto placed = forward_kinematics(sk, {{"j1", t1, 0}, {"j2", t2, 0}});
  const Vec3 tip = placed[2].apply({l0 + l1 + l2, 0, 0});
  const Vec3 expect{l0 + l1 * std::cos(t1) + l2 * std::cos(t1 + t2), -(l1 * std::sin(t1) + l2 * std::sin(t1 + t2)), 0};
  const double error = norm(tip - expect);
  std::printf("tip (%.15f, %.15f) m, closed form (%.15f, %.15f) m, error %.3g m\n", tip[0], tip[1], expect[0], expect[1], error);
  EXPECT_LT(error, 1e-12);
  // The root does not move; the middle link's far end sits at the second joint's new place.
  EXPECT_LT(norm(placed[0].apply({0.01, 0.02, 0.03}) - Vec3{0.01, 0.02, 0.03}), 1e-15);
  EXPECT_LT(norm(placed[1].apply({l0 + l1, 0, 0}) - Vec3{l0 + l1 * std::cos(t1), -l1 * std::sin(t1), 0}), 1e-12);
}

// Oracle: an abduction after a flexion about axes through the same centre is R_abd R_flex:
// flexing x by 90 degrees about -z gives -y, abducting that about -y leaves it.
TEST(Skeleton, AbductionTurnsAboutItsOwnAxis) {
  const Skeleton sk = planar_chain(0.05, 0.04, 0.025);
  const auto placed = forward_kinematics(sk, {{"j1", 0, M_PI / 2}});
  // Abduction of 90 degrees about -y turns x into +z (right-hand rule about -y: x -> z).
  const Vec3 d = placed[1].turn({1, 0, 0});
  std::printf("abducted direction (%.3g, %.3g, %.3g)\n", d[0], d[1], d[2]);
  EXPECT_LT(norm(d - Vec3{0, 0, 1}), 1e-15);
}

TEST(Skeleton, FileRoundTripAndChecks) {
  TempDir dir;
  const Skeleton sk = planar_chain(0.05, 0.04, 0.025);
  write_skeleton(dir / "s.json", sk);
  const Skeleton back = read_skeleton(dir / "s.json");
  ASSERT_EQ(back.bones.size(), 3u);
  ASSERT_EQ(back.joints.size(), 2u);
  EXPECT_EQ(back.bones[2].parent, "link1");
  EXPECT_EQ(back.joints[1].centre, sk.joints[1].centre);
  // A bone with no joint into it, a joint naming no bone, a parent that is no bone, an angle for no joint.
  Skeleton bad = sk;
  bad.joints.pop_back();
  EXPECT_THROW(validate_skeleton(bad, "t"), InputError);
  bad = sk;
  bad.joints[0].distal = "thumb";
  try {
    validate_skeleton(bad, "t");
    ADD_FAILURE() << "a joint naming no bone was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("joint 'j1'"), std::string::npos) << e.what();
  }
  bad = sk;
  bad.bones[1].parent = "radius";
  EXPECT_THROW(validate_skeleton(bad, "t"), InputError);
  EXPECT_THROW(forward_kinematics(sk, {{"j9", 0.1, 0}}), InputError);
}
