// core/stable_step: L_e = (sum |grad N_a|^2)^(-1/2) against closed forms, and its bracket
// h_min/2 <= L_e <= h_min (|grad N_a| = 1/h_a, the height over face a).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "tactus/core/stable_step.hpp"

using namespace tactus;

TEST(StableStep, RegularTetLengthIsEdgeOverSqrt6) {
  // Regular tet of edge a: every height h = a sqrt(2/3), so sum = 4/h^2 and L = h/2 = a/sqrt(6).
  const double a = 2e-3;
  const Vec3 x0{0, 0, 0}, x1{a, 0, 0}, x2{a / 2, a * std::sqrt(3.0) / 2, 0}, x3{a / 2, a * std::sqrt(3.0) / 6, a * std::sqrt(2.0 / 3.0)};
  EXPECT_NEAR(characteristic_length(x0, x1, x2, x3), a / std::sqrt(6.0), 1e-15);
}

TEST(StableStep, CornerTetLength) {
  // grad N = (-1,-1,-1), e1, e2, e3: sum = 3 + 1 + 1 + 1 = 6.
  EXPECT_NEAR(characteristic_length({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}), 1 / std::sqrt(6.0), 1e-15);
}

TEST(StableStep, BracketedByHalfAndFullSmallestHeight) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 1000; ++trial) {
    std::array<Vec3, 4> x;
    for (auto& p : x) p = {u(rng), u(rng), 0.05 * u(rng) + (&p == &x[3] ? 0.02 + 0.3 * std::abs(u(rng)) : 0)};
    const double V = std::abs(tet_volume(x[0], x[1], x[2], x[3]));
    if (V < 1e-6) continue;
    double hmin = 1e300;
    for (int f = 0; f < 4; ++f) {  // height over face opposite vertex f = 3V / area
      const Vec3 &p = x[(f + 1) % 4], &q = x[(f + 2) % 4], &r = x[(f + 3) % 4];
      const double e1[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, e2[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
      const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
      hmin = std::min(hmin, 3 * V / (0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])));
    }
    const double L = characteristic_length(x[0], x[1], x[2], x[3]);
    EXPECT_LE(L, hmin * (1 + 1e-12));
    EXPECT_GE(L, 0.5 * hmin * (1 - 1e-12));
  }
}

TEST(StableStep, CriticalStepPicksSmallestTetAndSlowestMaterial) {
  TetMesh m;
  m.nodes = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, -0.1}};
  m.tets = {{0, 1, 2, 3}, {0, 2, 1, 4}};
  m.tet_group = {1, 2};
  m.groups = {{3, 1, "soft"}, {3, 2, "bone"}};
  auto c = [](int g) { return g == 1 ? 1500.0 : 3000.0; };
  const CriticalStep s = critical_time_step(m, c);
  const double L1 = 1 / std::sqrt(6.0), L2 = characteristic_length(m.nodes[0], m.nodes[2], m.nodes[1], m.nodes[4]);
  const double expect = std::min(L1 / 1500, L2 / 3000);
  EXPECT_NEAR(s.dt, expect, 1e-18);
  EXPECT_EQ(s.element, L1 / 1500 < L2 / 3000 ? 0 : 1);
}

TEST(StableStep, DilatationalSpeed) {
  // nu = 0: K + 4mu/3 = E, so c = sqrt(E/rho).
  const double E = 1e6, rho = 1000, mu = E / 2, K = E / 3;
  EXPECT_NEAR(dilatational_wave_speed(K, mu, rho), std::sqrt(E / rho), 1e-12);
}
