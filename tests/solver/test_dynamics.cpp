// solver/dynamics: wave speed in a bar, energy conservation of a free body, cantilever frequency
// against the same mesh's eigenfrequency.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "linear_reference.hpp"
#include "material_kit.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/model_build.hpp"

using namespace tactus;
using namespace tactus::solver;
using namespace tactus::testkit;

namespace {
RunSpec run_until(double end_time) {
  RunSpec r;
  r.end_time = end_time;
  return r;
}
}  // namespace

// Oracle: with nu = 0 the bar's longitudinal wave speed is sqrt(E/rho) exactly (no lateral
// coupling). The half-amplitude front is timed at two stations 0.25 m apart; 2 % tolerance covers
// the smearing of the front by the lumped-mass dispersion over that distance.
TEST(Dynamics, BarWaveSpeed) {
  const double E = 1e7, rho = 1000, c = std::sqrt(E / rho), v0 = 0.01;
  const TetMesh mesh = samples::make_box_mesh(200, 1, 1, 1.0, 0.02, 0.02);
  Model model = build_model(mesh, linear_elastic(E, 0.0, rho));
  constrain_nodes(model, [](const double* X) { return X[0] < 1e-9; }, {true, false, false}, {v0, 0, 0});
  ExplicitSolver solver(model, run_until(0.009), DampingSpec{});
  const double stations[2] = {0.5, 0.75};
  double crossing[2] = {-1, -1}, previous[2] = {0, 0}, t_prev = 0;
  while (true) {
    solver.advance_velocity();
    const auto v = solver.velocity_at_step();
    for (int s = 0; s < 2; ++s) {
      double sum = 0;
      int count = 0;
      for (std::size_t i = 0; i < model.num_nodes; ++i)
        if (std::abs(model.X[3 * i] - stations[s]) < 1e-9) sum += v[3 * i], ++count;
      const double vs = sum / count;
      if (crossing[s] < 0 && vs >= 0.5 * v0)  // linear interpolation of the crossing time
        crossing[s] = t_prev + (solver.time() - t_prev) * (0.5 * v0 - previous[s]) / (vs - previous[s]);
      previous[s] = vs;
    }
    t_prev = solver.time();
    if (solver.time() >= 0.009 * (1 - 1e-12)) break;
    solver.advance_position();
  }
  ASSERT_GT(crossing[0], 0);
  ASSERT_GT(crossing[1], crossing[0]);
  const double measured = 0.25 / (crossing[1] - crossing[0]);
  std::printf("wave speed %.4f m/s (front between stations), %.4f m/s (from the end), sqrt(E/rho) %.4f m/s\n", measured, 0.5 / crossing[0], c);
  EXPECT_NEAR(measured / c, 1.0, 0.02) << "measured " << measured << " m/s, expected " << c;
  EXPECT_NEAR(0.5 / crossing[0] / c, 1.0, 0.02);
}

// Oracle: conservation. No damping, no loads: kinetic + strain energy stays at its initial value
// within 0.5 % over 10,000 steps of a large rotating and deforming motion.
TEST(Dynamics, FreeBodyConservesEnergy) {
  const TetMesh mesh = samples::make_box_mesh(4, 4, 4, 0.1, 0.1, 0.1);
  Model model = build_model(mesh, neo_hookean(3000.0, 50000.0, 1000.0));
  for (std::size_t i = 0; i < model.num_nodes; ++i) {
    const double x = model.X[3 * i] - 0.05, y = model.X[3 * i + 1] - 0.05, z = model.X[3 * i + 2] - 0.05;
    const double w = 2.0;  // rad/s spin about z, plus an expansion and a shear mode
    model.initial_velocity[3 * i] = -w * y + 0.3 * x + 0.2 * std::sin(31.4 * z);
    model.initial_velocity[3 * i + 1] = w * x + 0.1 * y;
    model.initial_velocity[3 * i + 2] = -0.2 * z + 0.1 * x * x / 0.05;
  }
  ExplicitSolver solver(model, run_until(1e9), DampingSpec{});
  const double E0 = solver.energies().initial;
  double worst = 0;
  for (int n = 0; n < 10000; ++n) {
    solver.advance_velocity();
    const Energies& e = solver.energies();
    worst = std::max(worst, std::abs(e.kinetic + e.internal - E0) / E0);
    solver.advance_position();
  }
  std::printf("largest relative energy drift over 10,000 steps: %.3e\n", worst);
  EXPECT_LE(worst, 0.005);
  EXPECT_EQ(solver.step_index(), 10000u);
}

// Oracle: the first eigenfrequency of the same mesh (independent small-strain stiffness and the
// lumped mass, dense generalized eigenproblem). The explicit run starts from that mode's shape as
// velocity (amplitude small enough to stay linear) and its frequency is timed from zero crossings
// over three periods. 1 % tolerance; the central-difference period error (w dt)^2/24 is ~1e-6.
TEST(Dynamics, CantileverFirstFrequencyMatchesEigenvalue) {
  const double E = 1e7, nu = 0.3, rho = 1000;
  const TetMesh mesh = samples::make_box_mesh(10, 2, 2, 0.1, 0.01, 0.01);
  Model model = build_model(mesh, linear_elastic(E, nu, rho));
  constrain_nodes(model, [](const double* X) { return X[0] < 1e-9; }, {true, true, true});
  const auto modes = testkit::generalized_modes(model, testkit::linear_stiffness(model, E, nu));
  const double omega = std::sqrt(modes.omega2[0]);
  Eigen::VectorXd shape = modes.shapes.col(0);
  Eigen::Index probe;
  shape.cwiseAbs().maxCoeff(&probe);
  shape *= 1e-4 / std::abs(shape[probe]);  // probe dof velocity amplitude 0.1 mm/s
  for (Eigen::Index i = 0; i < shape.size(); ++i) model.initial_velocity[static_cast<std::size_t>(i)] = shape[i];

  const double periods = 3.0, end = periods * 2 * M_PI / omega;
  ExplicitSolver solver(model, run_until(end * 1.1), DampingSpec{});
  std::vector<double> zeros;
  double prev_u = 0, prev_t = 0;
  while (solver.time() < end * 1.05) {
    solver.advance_velocity();
    const double u = solver.displacement()[static_cast<std::size_t>(probe)];
    // The displacement starts at 0 (velocity mode): record sign changes after the start.
    if (solver.step_index() > 1 && ((prev_u < 0) != (u < 0))) zeros.push_back(prev_t + (solver.time() - prev_t) * prev_u / (prev_u - u));
    prev_u = u, prev_t = solver.time();
    solver.advance_position();
  }
  ASSERT_GE(zeros.size(), 5u);
  const double half_periods = static_cast<double>(zeros.size() - 1);
  const double measured = M_PI * half_periods / (zeros.back() - zeros.front());
  std::printf("cantilever: explicit %.6f rad/s, eigen %.6f rad/s, ratio %.6f\n", measured, omega, measured / omega);
  EXPECT_NEAR(measured / omega, 1.0, 0.01) << "explicit " << measured << " rad/s, eigen " << omega << " rad/s";
}
