// The mesher's guarantees on label volumes that are not the phantom's (issue: "mesher guarantees on
// any label volume"): a thin curved bone shell 2-3 voxels thick (skull-like), a bone reaching the
// skin, and a 2-voxel speck label. Each is meshed the way tactus-mesh does it (small regions
// absorbed, then CGAL and the post-passes) and must meet, in every subdomain, a smallest dihedral
// angle of 10 deg and L_e min/median >= 0.2. Oracle: both recomputed from the node coordinates
// (mesh_guarantees.hpp), not read from the mesher's own report; the report's "guarantees" must
// agree.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "mesh_guarantees.hpp"
#include "tactus/mesher/image_mesher.hpp"
#include "tactus/mesher/small_regions.hpp"

using namespace tactus;

namespace {

constexpr double kVoxel = 0.5e-3;

// A ball of soft tissue (radius 14 mm) in a 64^3 volume of 0.5 mm voxels.
Volume<std::uint8_t> soft_ball() {
  Volume<std::uint8_t> v({64, 64, 64}, {kVoxel, kVoxel, kVoxel}, {0, 0, 0}, 0);
  for (int z = 0; z < 64; ++z)
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x)
        if (std::hypot(x - 31.5, y - 31.5, z - 31.5) * kVoxel < 14e-3) v.at(x, y, z) = 1;
  return v;
}

// Meshes like tactus-mesh and checks the guarantees in every label; prints what it compared.
void expect_guarantees(const char* name, const Volume<std::uint8_t>& labels, const LabelTable& table) {
  const auto [mesh, absorbed] = testkit::mesh_like_tactus_mesh(labels, table);
  std::printf("%s: %zu tets, %zu regions absorbed\n", name, mesh.tets.size(), absorbed);
  testkit::expect_mesh_guarantees(name, mesh);
}

}  // namespace

// A closed spherical shell of bone 2.5 voxels (1.25 mm) thick, radius 8-9.25 mm, soft tissue
// inside and out: a thin curved shell like a skull's.
TEST(MeshGuarantees, ThinCurvedBoneShell) {
  Volume<std::uint8_t> v = soft_ball();
  for (int z = 0; z < 64; ++z)
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) {
        const double r = std::hypot(x - 31.5, y - 31.5, z - 31.5) * kVoxel;
        if (r >= 8e-3 && r < 9.25e-3) v.at(x, y, z) = 2;
      }
  expect_guarantees("thin curved bone shell", v, {{0, "background"}, {1, "soft_tissue"}, {2, "bone_02"}});
}

// A bone rod (radius 3 mm, a rounded end at the centre) along x out through the skin: bone meets
// air where it crosses the skin.
TEST(MeshGuarantees, BoneReachingTheSkin) {
  Volume<std::uint8_t> v = soft_ball();
  for (int z = 0; z < 64; ++z)
    for (int y = 0; y < 64; ++y)
      for (int x = 32; x < 64; ++x)
        if (v.at(x, y, z) && std::hypot(std::max(0.0, 38.0 - x), y - 31.5, z - 31.5) * kVoxel < 3e-3) v.at(x, y, z) = 2;
  expect_guarantees("bone reaching the skin", v, {{0, "background"}, {1, "soft_tissue"}, {2, "bone_02"}});
}

// A 2-voxel label next to a regular bone: absorbed (with the warning tactus-mesh prints), the rest
// meshed within the guarantees.
TEST(MeshGuarantees, SpeckLabelAbsorbed) {
  Volume<std::uint8_t> v = soft_ball();
  for (int z = 26; z < 38; ++z)
    for (int y = 26; y < 38; ++y)
      for (int x = 20; x < 32; ++x) v.at(x, y, z) = 2;
  v.at(40, 31, 31) = 3, v.at(41, 31, 31) = 3;
  Volume<std::uint8_t> copy = v;
  const auto absorbed = mesher::absorb_small_regions(copy, mesher::min_region_voxels(copy, 0, mesher::ImageMeshParams{}.bone_cell_size_mm));
  ASSERT_EQ(absorbed.size(), 1u);
  EXPECT_EQ(absorbed[0].label, 3);
  EXPECT_EQ(absorbed[0].voxels, 2u);
  expect_guarantees("2-voxel speck beside a bone", v, {{0, "background"}, {1, "soft_tissue"}, {2, "bone_02"}, {3, "bone_03"}});
}
