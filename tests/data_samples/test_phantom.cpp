// data_samples/phantom: the synthetic hand has the paper's size and bone count, realistic
// Hounsfield values and noise, and is reproducible from its seed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
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
  for (int a = 0; a < 3; ++a) {
    const double extent = (hi[a] - lo[a] + 1) * p.truth.spacing[a] * 1e3;
    std::printf("axis %d: %.1f mm, the paper's hand %.2f mm (ratio %.3f)\n", a, extent, size[a], extent / size[a]);
    EXPECT_NEAR(extent / size[a], 1.0, 0.05) << "axis " << a;
  }
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

namespace {
samples::Phantom flexed(double degrees) {
  samples::PhantomParams params;
  params.voxel_mm = params.slice_mm = 1.4;
  params.noise_hu = 0;
  params.blur_voxels = 0;
  params.flexion_deg = degrees;
  return samples::make_hand_phantom(params);
}
}  // namespace

// Oracle: the phantom flexes each joint about its digit's own axis through the proximal bone's
// head centre, so forward kinematics of the 12-degree hand's joints.json, every finger joint
// (mcp, pip, dip) turned by 28 degrees and the thumb's mcp and ip by 0.8 x 28 (its rule), must
// give the 40-degree hand's bones and joints exactly (to rounding).
TEST(Phantom, FlexedHandIsTheStraightOneTurnedAboutItsJoints) {
  const Skeleton at12 = flexed(12).skeleton, at40 = flexed(40).skeleton;
  ASSERT_EQ(at12.bones.size(), 27u);
  ASSERT_EQ(at12.joints.size(), 19u);  // 4 x (cmc, mcp, pip, dip) + thumb (cmc, mcp, ip)
  std::vector<JointAngles> turn;
  for (const auto& j : at12.joints) {
    const bool thumb = j.name.find("thumb") != std::string::npos;
    if (j.name.rfind("cmc", 0) == 0) continue;
    turn.push_back({j.name, (thumb ? 0.8 : 1.0) * 28 * M_PI / 180, 0});
  }
  const auto placed = forward_kinematics(at12, turn);
  double worst_bone = 0, worst_joint = 0, worst_axis = 0;
  for (std::size_t b = 0; b < at12.bones.size(); ++b) {
    worst_bone = std::max(worst_bone, norm(placed[b].apply(at12.bones[b].centroid) - at40.bones[b].centroid));
    worst_axis = std::max(worst_axis, norm(placed[b].turn(at12.bones[b].long_axis) - at40.bones[b].long_axis));
  }
  for (std::size_t j = 0; j < at12.joints.size(); ++j) {
    const auto& parent = at12.joints[j].proximal;
    std::size_t p = 0;
    while (at12.bones[p].name != parent) ++p;
    worst_joint = std::max(worst_joint, norm(placed[p].apply(at12.joints[j].centre) - at40.joints[j].centre));
  }
  std::printf("12 -> 40 degrees by forward kinematics: bone centroids off by %.3g m, joint centres %.3g m, long axes %.3g\n", worst_bone, worst_joint,
              worst_axis);
  EXPECT_LT(worst_bone, 1e-12);
  EXPECT_LT(worst_joint, 1e-12);
  EXPECT_LT(worst_axis, 1e-12);
}

// Oracle: the volume grows with the posture, so no label reaches the volume's border (the wrist's
// cut at z = 0 aside) and every bone keeps its voxel count (a rigid motion keeps volume: within
// 12 %, the 1.4 mm grid's sampling of a 3-5 mm capsule, whose phase moves with the volume's
// origin; a clipped distal phalanx lost 22 %).
TEST(Phantom, FlexedHandIsNeverClipped) {
  const samples::Phantom straight = flexed(0);
  std::map<int, long> straight_count;
  for (auto l : straight.truth.data) ++straight_count[l];
  for (double degrees : {-20.0, 40.0, 70.0}) {
    const samples::Phantom p = flexed(degrees);
    const auto& t = p.truth;
    long on_border = 0;
    std::map<int, long> count;
    for (int z = 0; z < t.dims[2]; ++z)
      for (int y = 0; y < t.dims[1]; ++y)
        for (int x = 0; x < t.dims[0]; ++x) {
          const int l = t.at(x, y, z);
          ++count[l];
          const bool border = x == 0 || y == 0 || x == t.dims[0] - 1 || y == t.dims[1] - 1 || z == t.dims[2] - 1;
          if (l && border) ++on_border;
        }
    double worst = 0;
    std::string worst_bone;
    for (int l = 2; l < 29; ++l) {
      const double change = std::abs(static_cast<double>(count[l]) / static_cast<double>(straight_count[l]) - 1);
      if (change > worst) worst = change, worst_bone = p.labels.at(l);
    }
    std::printf("flexion %g: %ld labelled voxels on the border; largest change of a bone's voxel count %.2f %% (%s)\n", degrees, on_border,
                100 * worst, worst_bone.c_str());
    EXPECT_EQ(on_border, 0);
    EXPECT_LT(worst, 0.12);
  }
}
