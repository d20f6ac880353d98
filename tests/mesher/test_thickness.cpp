// mesher/thickness: the exact Euclidean distance transform against a brute-force search, a label's
// thickness against slabs of known thickness, --min-thickness-mm's absorption against the voxels
// of a fin built one voxel thick (all but its root column), and the refusal of a volume whose every label is thinner than
// its cells (the message names each label and its thickness).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "expect_error.hpp"
#include "tactus/mesher/thickness.hpp"

using namespace tactus;

TEST(Thickness, DistanceTransformEqualsBruteForceOnAnisotropicVoxels) {
  const std::array<int, 3> d{11, 9, 7};
  const std::array<double, 3> h{0.5e-3, 0.8e-3, 1.3e-3};
  std::vector<std::uint8_t> site(static_cast<std::size_t>(d[0] * d[1] * d[2]), 0);
  unsigned r = 12345;
  for (auto& s : site) s = ((r = r * 1103515245u + 12345u) >> 16) % 17 == 0;
  const std::vector<double> got = mesher::squared_distance_to_sites(site, d, h);
  double worst = 0;
  for (int k = 0; k < d[2]; ++k)
    for (int j = 0; j < d[1]; ++j)
      for (int i = 0; i < d[0]; ++i) {
        double best = std::numeric_limits<double>::infinity();
        for (int c = 0; c < d[2]; ++c)
          for (int b = 0; b < d[1]; ++b)
            for (int a = 0; a < d[0]; ++a)
              if (site[static_cast<std::size_t>(a + d[0] * (b + d[1] * c))])
                best = std::min(best, std::pow((a - i) * h[0], 2) + std::pow((b - j) * h[1], 2) + std::pow((c - k) * h[2], 2));
        worst = std::max(worst, std::abs(got[static_cast<std::size_t>(i + d[0] * (j + d[1] * k))] - best));
      }
  std::printf("  largest difference from brute force: %.3g m^2\n", worst);
  EXPECT_LT(worst, 1e-18);
}

namespace {
// A 1 mm volume 20 x 20 x n: label 1 fills it except a slab of `slab` voxels of label 2 across z.
Volume<std::uint8_t> slab_volume(int slab, int n = 20) {
  Volume<std::uint8_t> v({20, 20, n}, {1e-3, 1e-3, 1e-3}, {0, 0, 0}, 1);
  for (int k = 0; k < slab; ++k)
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 20; ++i) v.at(i, j, 8 + k) = 2;
  return v;
}
}  // namespace

TEST(Thickness, SlabsMeasureTheirVoxelCount) {
  for (int slab : {1, 2, 3, 5}) {
    const auto t = mesher::label_thickness(slab_volume(slab));
    std::printf("  slab of %d voxel(s): thickness %.3f mm\n", slab, t.at(2).thickness_m * 1e3);
    // Odd counts exactly (2r + 1); an even count's deepest voxel is (n/2 - 1) from its boundary.
    EXPECT_NEAR(t.at(2).thickness_m, (slab % 2 ? slab : slab - 1) * 1e-3, 1e-12);
  }
}

TEST(Thickness, MinThicknessMovesAOneVoxelFinAndNothingElse) {
  Volume<std::uint8_t> v({24, 24, 24}, {1e-3, 1e-3, 1e-3}, {0, 0, 0}, 0);
  std::size_t fin = 0;
  for (int k = 4; k < 20; ++k)
    for (int j = 4; j < 20; ++j)
      for (int i = 4; i < 12; ++i) v.at(i, j, k) = 1;  // a block 8 voxels thick
  for (int k = 8; k < 16; ++k)
    for (int i = 12; i < 20; ++i) v.at(i, 12, k) = 1, ++fin;  // a fin one voxel thick sticking out of it
  const auto parts = mesher::absorb_thin_parts(v, 3e-3);
  ASSERT_EQ(parts.size(), 1u);
  std::printf("  fin of %zu voxels; moved %zu (into background %zu)\n", fin, parts[0].voxels,
              parts[0].into.count(0) ? parts[0].into.at(0) : std::size_t{0});
  // The fin's root column (8 voxels) stays: the block's face voxels behind it are interior once the
  // fin is there, so the block's core reaches one voxel from the root, within the ball's reach.
  EXPECT_EQ(parts[0].voxels, fin - 8);
  EXPECT_EQ(parts[0].into.at(0), fin - 8);
  std::size_t left = 0;
  for (auto x : v.data) left += x == 1;
  EXPECT_EQ(left, 8u * 16u * 16u + 8u);
}

TEST(Thickness, EveryLabelThinnerThanItsCellsIsRefused) {
  Volume<std::uint8_t> v({30, 30, 30}, {1e-3, 1e-3, 1e-3}, {0, 0, 0}, 0);
  for (int k = 10; k < 12; ++k)
    for (int j = 2; j < 28; ++j)
      for (int i = 2; i < 28; ++i) v.at(i, j, k) = k == 10 ? 1 : 2;  // two one-voxel sheets
  mesher::ImageMeshParams p;                                         // cells 7 mm and 3.5 mm
  testkit::expect_input_error(
      [&] {
        mesher::fit_thin_labels(v, {{1, "soft_tissue"}, {2, "bone_02"}}, p, 0, "labels.h5");
      },
      {"every label thinner than one element", "'soft_tissue' 1 mm (cells 7 mm)", "'bone_02' 1 mm (cells 3.5 mm)"});
}
