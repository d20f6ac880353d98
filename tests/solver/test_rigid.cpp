// Rigid bodies (issue "rigid bodies and faster kernels", item 1; solver/include/tactus/solver/rigid.hpp).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "scenario_kit.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/model_build.hpp"
#include "tactus/solver/rigid.hpp"

using namespace tactus;
using namespace tactus::solver;

namespace {

Material rigid_material(double density) {
  MaterialValues v;
  v.numbers["density"] = density;
  return Material::make("rigid", v);
}

// The complete elliptic integral of the first kind, K(k) = pi / (2 AGM(1, sqrt(1 - k^2))).
double elliptic_k(double k) {
  double a = 1, b = std::sqrt(1 - k * k);
  for (int i = 0; i < 60 && std::abs(a - b) > 1e-16 * a; ++i) {
    const double m = 0.5 * (a + b);
    b = std::sqrt(a * b), a = m;
  }
  return M_PI / (2 * a);
}

}  // namespace

// Oracle: the torque-free rigid body (Landau & Lifshitz, Mechanics §37). A 40 x 20 x 10 mm box of
// rigid tets spins about its intermediate principal axis (y) with a small perturbation, at
// Omega dt = 0.01; it flips over and back with the period of the elliptic-function solution,
// T = 4 K(k) sqrt(I1 I2 I3 / ((I3 - I2)(L^2 - 2 E I1))), k^2 = (I2 - I1)(2 E I3 - L^2) / ((I3 - I2)(L^2 - 2 E I1))
// (the case L^2 > 2 E I2). Over ten flips: the spatial angular momentum conserved to 1e-12 sqrt(N)
// relative, the kinetic energy without drift (<= 1e-5), the period within 1 %.
TEST(Rigid, TorqueFreeFlipAboutTheIntermediateAxis) {
  const double lx = 0.04, ly = 0.02, lz = 0.01, rho = 7800, omega = 20.0;
  Model model = build_model(samples::make_box_mesh(8, 4, 2, lx, ly, lz), rigid_material(rho));
  const Vec3 w{0.02 * omega, omega, 0.03 * omega};
  model.bodies[0].initial_angular_velocity = w;
  for (std::size_t i = 0; i < model.num_nodes; ++i) {
    const Vec3 r{model.X[3 * i] - lx / 2, model.X[3 * i + 1] - ly / 2, model.X[3 * i + 2] - lz / 2};
    const Vec3 v = cross(w, r);
    for (int d = 0; d < 3; ++d) model.initial_velocity[3 * i + d] = v[d];
  }
  const double dt = 0.01 / omega;
  RunSpec run;
  run.end_time = 1e9;
  run.time_step = dt;
  ExplicitSolver solver(model, run, DampingSpec{});
  ASSERT_EQ(solver.rigid_bodies().size(), 1u);
  const RigidBody& b = solver.rigid_bodies()[0];
  // Exact inertia of the box from its tets.
  const double m = rho * lx * ly * lz;
  const double I1 = m * (ly * ly + lz * lz) / 12, I2 = m * (lx * lx + lz * lz) / 12, I3 = m * (lx * lx + ly * ly) / 12;
  EXPECT_NEAR(b.mass, m, 1e-12 * m);
  EXPECT_NEAR(b.principal[0], I1, 1e-10 * I3);
  EXPECT_NEAR(b.principal[1], I2, 1e-10 * I3);
  EXPECT_NEAR(b.principal[2], I3, 1e-10 * I3);
  const Vec3d L0 = b.angular_momentum;
  const double E0 = solver.energies().kinetic;
  const double L2 = L0.squaredNorm();
  ASSERT_GT(L2, 2 * E0 * I2);
  const double k2 = (I2 - I1) * (2 * E0 * I3 - L2) / ((I3 - I2) * (L2 - 2 * E0 * I1));
  const double period = 4 * elliptic_k(std::sqrt(k2)) * std::sqrt(I1 * I2 * I3 / ((I3 - I2) * (L2 - 2 * E0 * I1)));
  // The body-frame angular momentum along the intermediate axis: its upward zero crossings.
  auto pi2 = [&]() { return ((b.rotation * b.axes).transpose() * b.angular_momentum)[1]; };
  std::vector<double> crossings;
  double before = pi2(), worst_L = 0, e_min = E0, e_max = E0, e_first_flip = 0;
  std::size_t n = 0;
  while (crossings.size() < 11) {
    solver.advance_velocity();
    const double e = solver.energies().kinetic;
    e_min = std::min(e_min, e), e_max = std::max(e_max, e);
    worst_L = std::max(worst_L, (b.angular_momentum - L0).norm() / L0.norm());
    solver.advance_position();
    ++n;
    const double now = pi2();
    if (before < 0 && now >= 0) {
      crossings.push_back(solver.time() - dt * now / (now - before));
      if (crossings.size() == 1) e_first_flip = e;
    }
    before = now;
    ASSERT_LT(n, 10000000u) << "no flips";
  }
  const double measured = (crossings.back() - crossings.front()) / 10.0;
  const double drift = std::abs(solver.energies().kinetic - e_first_flip) / E0;
  std::printf("torque-free flip: I = %.6g %.6g %.6g kg m^2, Omega dt = %.3g, %zu steps, 10 periods\n", I1, I2, I3, omega * dt, n);
  std::printf("  period %.6f s vs elliptic %.6f s (%+.4f %%); |L - L0| / |L0| <= %.2e (1e-12 sqrt(N) = %.2e)\n", measured, period,
              100 * (measured / period - 1), worst_L, 1e-12 * std::sqrt(static_cast<double>(n)));
  std::printf("  kinetic energy range %.2e of E0, drift over ten periods %.2e\n", (e_max - e_min) / E0, drift);
  EXPECT_NEAR(measured / period, 1.0, 0.01);
  EXPECT_LE(worst_L, 1e-12 * std::sqrt(static_cast<double>(n)));
  EXPECT_LE(drift, 1e-5);
}

namespace {

// A soft cube (neo-Hookean) with a ball of tets at its centre of material `inclusion`, compressed
// 4 % quasi-statically between a fixed base and a top pressed down by a smooth ramp and held,
// until the kinetic energy is below 1e-8 of the strain energy. Returns the displacements.
std::vector<double> compressed_with_inclusion(const MaterialInstance& inclusion, std::size_t& rigid_bodies, double& seconds) {
  testkit::TempDir dir;
  const double L = 0.02, radius = 0.005;
  TetMesh mesh = samples::make_box_mesh(8, 8, 8, L, L, L);
  mesh.groups.push_back({3, 2, "inclusion"});
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    Vec3 c{0, 0, 0};
    for (int a = 0; a < 4; ++a)
      for (int d = 0; d < 3; ++d) c[d] += 0.25 * mesh.nodes[static_cast<std::size_t>(mesh.tets[e][a])][d];
    if (std::hypot(c[0] - L / 2, c[1] - L / 2, c[2] - L / 2) < radius) mesh.tet_group[e] = 2;
  }
  Scenario sc;
  sc.file = dir.path() / "s.toml";
  BodySpec body = testkit::body_from_mesh(dir, "block", mesh, "soft");
  body.materials["inclusion"] = inclusion.name;
  sc.bodies.push_back(body);
  sc.materials["soft"] = MaterialInstance{"soft", "neo_hookean", {{{"mu", 1e5}, {"bulk", 1e6}, {"density", 1000}}, {}}};
  sc.materials[inclusion.name] = inclusion;
  sc.run.end_time = 1.0;
  sc.damping.alpha = 2000;
  CurveSpec ramp;
  ramp.name = "ramp", ramp.smooth_step = true, ramp.t0 = 0, ramp.t1 = 0.01;
  sc.curves["ramp"] = ramp;
  sc.boundaries.push_back(testkit::boundary("block", "zmin", solver::BoundaryType::fixed, {true, true, true}, "base"));
  BoundarySpec top = testkit::boundary("block", "zmax", solver::BoundaryType::displacement, {true, true, true}, "top");
  top.displacement = {0, 0, -0.04 * L};
  top.curve = "ramp";
  sc.boundaries.push_back(top);
  const Model m = build_model(sc);
  ExplicitSolver s(m, sc.run, sc.damping);
  rigid_bodies = s.rigid_bodies().size();
  const auto t0 = std::chrono::steady_clock::now();
  testkit::run_to_rest(s, 0.01, 1e-8);
  seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<double> u(3 * m.num_nodes);  // in input numbering, to compare the two models
  for (std::size_t i = 0; i < m.num_nodes; ++i)
    for (int d = 0; d < 3; ++d)
      u[3 * i + static_cast<std::size_t>(d)] = s.displacement()[3 * static_cast<std::size_t>(m.node_of_input[i]) + static_cast<std::size_t>(d)];
  return u;
}

}  // namespace

// Oracle: the same body with the ball made of a deformable material 1,000 times stiffer than the
// matrix (E = 2.9e8 Pa vs the matrix's 2.9e5): a rigid ball tied to the matrix through its nodes
// must give the same displacement field, every node within 2 % of the largest displacement.
TEST(Rigid, EmbeddedRigidBallMatchesAVeryStiffOne) {
  std::size_t rigid = 0, stiff_rigid = 0;
  double t_rigid = 0, t_stiff = 0;
  const std::vector<double> u_rigid = compressed_with_inclusion({"ball", "rigid", {{{"density", 1000}}, {}}}, rigid, t_rigid);
  const std::vector<double> u_stiff =
      compressed_with_inclusion({"ball", "linear_elastic", {{{"E", 2.9e8}, {"nu", 0.3}, {"density", 1000}}, {}}}, stiff_rigid, t_stiff);
  double largest = 0, worst = 0;
  for (std::size_t i = 0; i < u_rigid.size(); i += 3) {
    largest = std::max(largest, std::hypot(u_stiff[i], u_stiff[i + 1], u_stiff[i + 2]));
    worst = std::max(worst, std::hypot(u_rigid[i] - u_stiff[i], u_rigid[i + 1] - u_stiff[i + 1], u_rigid[i + 2] - u_stiff[i + 2]));
  }
  std::printf(
      "embedded ball: %zu rigid body; largest |u| %.4g m; largest |u_rigid - u_stiff| %.3g m = %.3f %% of it; wall %.2f s (rigid) vs %.2f s "
      "(stiff)\n",
      rigid, largest, worst, 100 * worst / largest, t_rigid, t_stiff);
  EXPECT_EQ(rigid, 1u);
  EXPECT_EQ(stiff_rigid, 0u);
  EXPECT_LE(worst, 0.02 * largest);
}

// The seam for joint-driven motion (RigidBodies::prescribe): one piece turned about a pivot that
// is not its centre, as a phalanx turns about its joint. Oracle: rotation about a fixed axis. A
// 40 x 20 x 10 mm rigid box turns at w = 2 rad/s about the z axis through its corner (0, 0, 0) for
// pi / 4 s (a quarter turn) in 1000 steps, while the pivot also moves at 0.01 m/s along z: its
// centre ends at Rz(pi/2) c0 + (0, 0, 0.01 pi/4), its rotation Rz(pi/2), to round-off.
TEST(Rigid, PrescribedPieceTurnsAboutItsPivot) {
  const double lx = 0.04, ly = 0.02, lz = 0.01, w = 2.0, vz = 0.01;
  Model model = build_model(samples::make_box_mesh(8, 4, 2, lx, ly, lz), rigid_material(1000));
  const double end = M_PI / (2 * w);
  RunSpec run;
  run.end_time = 1e9;
  run.time_step = end / 1000;
  ExplicitSolver solver(model, run, DampingSpec{});
  RigidMotion motion;
  motion.velocity = Vec3d(0, 0, vz), motion.angular_velocity = Vec3d(0, 0, w), motion.pivot = Vec3d::Zero();
  solver.prescribe_rigid_motion(0, motion);
  const RigidBody& b = solver.rigid_bodies()[0];
  const Vec3d c0 = b.centre0;
  for (int n = 0; n < 1000; ++n) solver.advance_velocity(), solver.advance_position();
  const Vec3d expected(-c0[1], c0[0], c0[2] + vz * end);
  Mat3 quarter;
  quarter << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const double centre_error = (b.centre - expected).norm(), rotation_error = (b.rotation - quarter).norm();
  std::printf("pivoted quarter turn: centre (%.9f, %.9f, %.9f) vs (%.9f, %.9f, %.9f) m, |c - c*| = %.2e m, |R - Rz(90)| = %.2e\n", b.centre[0],
              b.centre[1], b.centre[2], expected[0], expected[1], expected[2], centre_error, rotation_error);
  EXPECT_LT(centre_error, 1e-12);
  EXPECT_LT(rotation_error, 1e-12);
  // Every node sits where the turned box puts it.
  double worst = 0;
  for (std::size_t i = 0; i < model.num_nodes; ++i) {
    const Vec3d X(&model.X[3 * i]), x = X + Vec3d(&solver.displacement()[3 * i]);
    worst = std::max(worst, (x - (quarter * X + Vec3d(0, 0, vz * end))).norm());
  }
  std::printf("  largest node position error %.2e m\n", worst);
  EXPECT_LT(worst, 1e-12);
}
