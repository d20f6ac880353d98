// data_samples/phantom: the synthetic hand has the paper's size and bone count, realistic
// Hounsfield values and noise, and is reproducible from its seed.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "tactus/data_samples/phantom.hpp"
#include "temp_dir.hpp"

using namespace tactus;

namespace {
const samples::Phantom& coarse() {  // 1.4 mm voxels: fast, enough for the geometry checks
  static const samples::Phantom p = [] {
    samples::PhantomParams params;
    params.voxel_mm = params.slice_mm = 1.4;
    return samples::make_hand_phantom(params);
  }();
  return p;
}
}  // namespace

// Oracle: the paper's hand, L1 = 159.23 mm wide, L2 = 230.12 mm long, L3 = 77.68 mm thick (§3.2),
// within 5 % (one voxel of the coarse grid is 1.4 mm).
TEST(Phantom, PaperDimensionsAndBoneCount) {
  const auto& p = coarse();
  int lo[3] = {1 << 30, 1 << 30, 1 << 30}, hi[3] = {-1, -1, -1};
  std::set<int> bones;
  for (int z = 0; z < p.truth.dims[2]; ++z)
    for (int y = 0; y < p.truth.dims[1]; ++y)
      for (int x = 0; x < p.truth.dims[0]; ++x) {
        const int l = p.truth.at(x, y, z);
        if (!l) continue;
        const int c[3] = {x, y, z};
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a]), hi[a] = std::max(hi[a], c[a]);
        if (l >= 2) bones.insert(l);
      }
  const double size[3] = {159.23, 77.68, 230.12};
  for (int a = 0; a < 3; ++a) EXPECT_NEAR((hi[a] - lo[a] + 1) * p.truth.spacing[a] * 1e3 / size[a], 1.0, 0.05) << "axis " << a;
  EXPECT_EQ(bones.size(), 27u);
  int carpals = 0, metacarpals = 0, phalanges = 0;
  for (const auto& [id, name] : p.labels) {
    if (id < 2) continue;
    if (name.find("metacarpal") != std::string::npos)
      ++metacarpals;
    else if (name.find("phalanx") != std::string::npos)
      ++phalanges;
    else
      ++carpals;
  }
  EXPECT_EQ(carpals, 8);
  EXPECT_EQ(metacarpals, 5);
  EXPECT_EQ(phalanges, 14);
}

// Oracle: the HU written for each tissue and the requested noise. Deep inside tissue classes the
// blur has no effect, so the sample mean is the class value and the sample deviation the noise.
TEST(Phantom, HounsfieldValuesAndNoiseLevel) {
  samples::PhantomParams params;
  params.voxel_mm = params.slice_mm = 1.4;
  params.noise_hu = 30;
  const auto p = samples::make_hand_phantom(params);
  double air_sum = 0, air_sq = 0;
  long air_n = 0;
  for (int z = 0; z < p.ct.dims[2]; ++z)
    for (int y = 0; y < 2; ++y)  // the first rows are air, far from the hand
      for (int x = 0; x < p.ct.dims[0]; ++x) {
        const double v = p.ct.at(x, y, z);
        air_sum += v, air_sq += v * v, ++air_n;
      }
  const double mean = air_sum / static_cast<double>(air_n);
  const double sd = std::sqrt(air_sq / static_cast<double>(air_n) - mean * mean);
  // Stored values stop at -1024 HU (the 16-bit stack's zero), as on a scanner: air is a normal
  // N(-1000, 30) clamped below at c = -1024. Its moments, with a = (c - mu) / sigma:
  //   E[X] = c Phi(a) + mu (1 - Phi(a)) + sigma phi(a),
  //   E[X^2] = c^2 Phi(a) + (mu^2 + sigma^2)(1 - Phi(a)) + sigma (mu + c) phi(a).
  const double mu = samples::PhantomHu::air, sigma = 30, c = -1024, a = (c - mu) / sigma;
  const double Phi = 0.5 * std::erfc(-a / std::sqrt(2.0)), phi = std::exp(-0.5 * a * a) / std::sqrt(2 * M_PI);
  const double m1 = c * Phi + mu * (1 - Phi) + sigma * phi;
  const double m2 = c * c * Phi + (mu * mu + sigma * sigma) * (1 - Phi) + sigma * (mu + c) * phi;
  // Tolerances: ~4 standard errors for ~30k samples (integer rounding adds 1/12 HU^2).
  EXPECT_NEAR(mean, m1, 0.6);
  EXPECT_NEAR(sd, std::sqrt(m2 - m1 * m1), 0.6);
  EXPECT_GE(p.ct.dims[2], 150);
}

TEST(Phantom, ReproducibleFromSeed) {
  samples::PhantomParams params;
  params.voxel_mm = params.slice_mm = 2.0;
  const auto a = samples::make_hand_phantom(params), b = samples::make_hand_phantom(params);
  EXPECT_EQ(a.ct.data, b.ct.data);
  params.seed = 2;
  const auto c = samples::make_hand_phantom(params);
  EXPECT_NE(a.ct.data, c.ct.data);
  EXPECT_EQ(a.truth.data, c.truth.data);  // the anatomy does not depend on the noise seed
}

TEST(Phantom, SliceStackFormat) {
  testkit::TempDir dir;
  samples::PhantomParams params;
  params.voxel_mm = params.slice_mm = 3.0;
  const auto p = samples::make_hand_phantom(params);
  samples::write_slice_stack(p.ct, dir / "stack");
  std::ifstream in(dir / "stack" / "stack.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_DOUBLE_EQ(j["spacing_mm"][0].get<double>(), 3.0);
  EXPECT_DOUBLE_EQ(j["rescale_intercept"].get<double>(), -1024.0);
  EXPECT_EQ(j["slices"].get<int>(), p.ct.dims[2]);
  EXPECT_TRUE(std::filesystem::exists(dir / "stack" / "slice_0000.png"));
}
