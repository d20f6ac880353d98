// solver/mass scaling: run.minimum_time_step adds mass to the tets whose stable step is below it,
// as explicit codes do. Oracles: the added mass computed independently from the element steps of
// core's stable-step function, the step the solver then takes, momentum and energy bookkeeping of
// the added mass, and the stop at the user's limit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "material_kit.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/stable_step.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/model_build.hpp"

using namespace tactus;
using namespace tactus::solver;
using namespace tactus::testkit;

namespace {

constexpr double kMu = 3000, kBulk = 50000, kRho = 1000;

Model irregular_box() {
  TetMesh mesh = samples::make_box_mesh(5, 5, 5, 0.05, 0.05, 0.05);
  samples::perturb_interior_nodes(mesh, 0.01, 0.35, 17);  // some tets much smaller than others
  return build_model(mesh, neo_hookean(kMu, kBulk, kRho, "standard"));
}

// Each tet's stable step in the undeformed mesh: L_e / c (core/stable_step.hpp), model numbering.
std::vector<double> element_steps(const Model& m) {
  const double c = dilatational_wave_speed(kBulk, kMu, kRho);
  std::vector<double> dt(m.num_elements);
  for (std::size_t e = 0; e < m.num_elements; ++e) {
    Vec3 x[4];
    for (int a = 0; a < 4; ++a)
      for (int d = 0; d < 3; ++d) x[a][d] = m.X[3 * static_cast<std::size_t>(m.conn[4 * e + a]) + d];
    dt[e] = characteristic_length(x[0], x[1], x[2], x[3]) / c;
  }
  return dt;
}

// Mass scaling against the element estimate alone (the oracle below is each tet's deficit; with
// the nodal bound on, scaling starts only once the larger of the two falls below the floor).
RunSpec scaled_run(double floor, double limit) {
  RunSpec r;
  r.end_time = 1e9;
  r.threads = 1;
  r.step_estimate = StepEstimate::element;
  r.minimum_time_step = floor;
  r.added_mass_limit = limit;
  return r;
}

}  // namespace

// Oracle: a tet of step dt_e < floor needs rho V_e (floor^2 / dt_e^2 - 1) more mass (its step
// grows as the square root of its mass); the run's added mass must be their sum, and its step
// the floor.
TEST(MassScaling, AddedMassIsTheElementStepDeficit) {
  Model m = irregular_box();
  const std::vector<double> dt = element_steps(m);
  std::vector<double> sorted = dt;
  std::sort(sorted.begin(), sorted.end());
  const double floor = sorted[sorted.size() / 10];  // a tenth of the tets below it
  double expected = 0, mass = 0;
  std::size_t below = 0;
  for (std::size_t e = 0; e < m.num_elements; ++e) {
    mass += kRho * m.volume[e];
    if (dt[e] < floor) expected += kRho * m.volume[e] * (floor * floor / (dt[e] * dt[e]) - 1), ++below;
  }
  const ExplicitSolver s(m, scaled_run(floor, 1.0), DampingSpec{});
  double nodal = 0;
  for (double x : s.nodal_mass()) nodal += x;
  std::printf(
      "mass scaling: %zu of %zu tets below the floor %.4e s (smallest step %.4e s); added %.6e kg, expected %.6e kg (%.3f %% of %.4e kg); "
      "step now %.6e s\n",
      below, m.num_elements, floor, sorted.front(), s.added_mass()[0], expected, 100 * expected / mass, mass, s.critical_step());
  EXPECT_GT(below, 10u);
  EXPECT_NEAR(s.added_mass()[0], expected, 1e-9 * expected);
  EXPECT_NEAR(s.body_mass()[0], mass, 1e-12 * mass);
  EXPECT_NEAR(nodal, mass + expected, 1e-12 * mass);
  EXPECT_NEAR(s.critical_step(), floor, 1e-12 * floor);
}

// Oracle: bookkeeping. A free box, spun and squeezed by its initial velocity, so tets keep falling
// below the floor during the run: with no external force the momentum of the scaled masses must be
// the initial physical momentum plus what the added mass brought (dm v^{n-1/2}, which the update
// conserves) to round-off, and the energy balance, which books 1/2 dm v^2, must close as well as
// the scheme's own does in this violent motion: within 1e-3 of the energy (the same run without
// scaling: printed).
TEST(MassScaling, AddedMassMomentumAndEnergyAreBooked) {
  Model m = irregular_box();
  const std::vector<double> dt = element_steps(m);
  const double floor = *std::min_element(dt.begin(), dt.end()) * 1.5;
  Vec3 p0{0, 0, 0};
  double p_scale = 0;
  for (std::size_t i = 0; i < m.num_nodes; ++i) {
    const double x = m.X[3 * i] - 0.025, y = m.X[3 * i + 1] - 0.025, z = m.X[3 * i + 2] - 0.025;
    m.initial_velocity[3 * i] = -20 * x - 2 * y + 0.3;
    m.initial_velocity[3 * i + 1] = -20 * y + 2 * x;
    m.initial_velocity[3 * i + 2] = -20 * z + 0.1;
    for (int d = 0; d < 3; ++d) p0[d] += m.mass[i] * m.initial_velocity[3 * i + d], p_scale += m.mass[i] * std::abs(m.initial_velocity[3 * i + d]);
  }
  struct Outcome {
    double added_at_start = 0, added = 0, kinetic_brought = 0, worst_balance = 0, momentum_error = 0, step = 0;
  };
  auto run = [&](double minimum_step) {
    ExplicitSolver s(m, scaled_run(minimum_step, 1.0), DampingSpec{});
    Outcome o;
    o.added_at_start = s.added_mass()[0];
    for (int n = 0; n < 3000; ++n) {
      s.advance_velocity();
      o.worst_balance = std::max(o.worst_balance, std::abs(s.energies().balance_error()) / s.energies().scale());
      const auto v = s.velocity_at_step();
      Vec3 p{0, 0, 0};
      for (std::size_t i = 0; i < m.num_nodes; ++i)
        for (int d = 0; d < 3; ++d) p[d] += s.nodal_mass()[i] * v[3 * i + d];
      for (int d = 0; d < 3; ++d) o.momentum_error = std::max(o.momentum_error, std::abs(p[d] - p0[d] - s.added_momentum()[d]));
      s.advance_position();
    }
    o.added = s.added_mass()[0], o.kinetic_brought = s.energies().added_mass_kinetic, o.step = s.critical_step();
    return o;
  };
  const Outcome scaled = run(floor), plain = run(1e-12);  // 1e-12 s: scaling on, never needed
  std::printf(
      "mass scaling over 3000 steps: added %.4e kg at the start, %.4e kg in all; kinetic energy brought %.3e J; largest balance error "
      "%.2e of the energy (%.2e without scaling); momentum error %.2e of sum m |v|\n",
      scaled.added_at_start, scaled.added, scaled.kinetic_brought, scaled.worst_balance, plain.worst_balance, scaled.momentum_error / p_scale);
  EXPECT_EQ(plain.added, 0.0);
  EXPECT_GT(scaled.added, scaled.added_at_start);  // tets fell below the floor during the run
  EXPECT_GE(scaled.step, floor * (1 - 1e-12));
  EXPECT_LE(scaled.worst_balance, 1e-3);
  EXPECT_LE(scaled.momentum_error, 1e-12 * p_scale);
}

// A floor that needs more mass than the limit stops the run, naming the body and the keys.
TEST(MassScaling, LimitStopsTheRunWithAMessage) {
  const Model m = irregular_box();
  const std::vector<double> dt = element_steps(m);
  const double floor = *std::max_element(dt.begin(), dt.end()) * 2;  // every tet below: +300 % at least
  try {
    const ExplicitSolver s(m, scaled_run(floor, 0.01), DampingSpec{});
    FAIL() << "no stop";
  } catch (const NumericalError& e) {
    const std::string what = e.what();
    std::printf("message: %s\n", what.c_str());
    EXPECT_NE(what.find("body 'body'"), std::string::npos);
    EXPECT_NE(what.find("run.added_mass_limit = 1 %"), std::string::npos);
    EXPECT_NE(what.find("run.minimum_time_step"), std::string::npos);
  }
}
