// solver/loading: time curves, prescribed displacements, follower pressures, reactions, body
// rotation and Rayleigh damping, each against an analytic or independently computed reference.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>

#include "scenario_kit.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/model_build.hpp"
#include "temp_dir.hpp"

using namespace tactus;
using namespace tactus::solver;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A scenario of one body meshed by `mesh` (written next to the scenario), made of `material`.
Scenario one_body(const testkit::TempDir& dir, const TetMesh& mesh, const MaterialInstance& material) {
  Scenario sc;
  sc.file = dir.path() / "case.toml";
  sc.materials[material.name] = material;
  sc.bodies.push_back(testkit::body_from_mesh(dir, "body", mesh, material.name));
  return sc;
}

CurveSpec table(const std::string& name, std::vector<double> t, std::vector<double> v) {
  CurveSpec c;
  c.name = name, c.times = std::move(t), c.values = std::move(v);
  return c;
}

CurveSpec smooth_step(const std::string& name, double t0, double t1) {
  CurveSpec c;
  c.name = name, c.smooth_step = true, c.t0 = t0, c.t1 = t1;
  return c;
}

// Steps until `done` (checked at every t^n) or the end time; returns the steps taken.
std::size_t run_until(ExplicitSolver& s, const std::function<bool()>& done) {
  std::size_t n = 0;
  while (true) {
    s.advance_velocity();
    if (done() || s.finished()) return n;
    s.advance_position();
    ++n;
  }
}

}  // namespace

// Curves: the table interpolates and holds its ends; the smooth step and both integrals against
// their closed forms.
TEST(Loading, CurvesAndTheirIntegrals) {
  const CurveSpec t = table("t", {1.0, 2.0, 4.0}, {0.0, 2.0, -1.0});
  EXPECT_DOUBLE_EQ(t.at(0.5), 0.0);
  EXPECT_DOUBLE_EQ(t.at(1.5), 1.0);
  EXPECT_DOUBLE_EQ(t.at(3.0), 0.5);
  EXPECT_DOUBLE_EQ(t.at(9.0), -1.0);
  // integral to 5: 0 (to 1) + 1 (1..2) + 1 (2..4: from 2 to -1) - 1 (4..5)
  EXPECT_NEAR(t.integral(5.0), 1.0, 1e-15);
  EXPECT_NEAR(t.integral(1.5), 0.25, 1e-15);
  const CurveSpec s = smooth_step("s", 1.0, 3.0);
  EXPECT_DOUBLE_EQ(s.at(0.5), 0.0);
  EXPECT_DOUBLE_EQ(s.at(2.0), 0.5);
  EXPECT_DOUBLE_EQ(s.at(3.5), 1.0);
  EXPECT_NEAR(s.integral(2.0), 2.0 * (0.125 - 0.5 * 0.0625), 1e-15);  // h (s^3 - s^4/2) at s = 1/2
  EXPECT_NEAR(s.integral(4.0), 2.0 * 0.5 + 1.0, 1e-15);
  std::printf("curves: table integral to 5 s = %.15g (exact 1), smooth step integral to 4 s = %.15g (exact 2)\n", t.integral(5.0), s.integral(4.0));
}

// A displacement boundary on a curve: its nodes are exactly at value x curve(t^n) at every step.
TEST(Loading, DisplacementBoundaryFollowsItsCurveExactly) {
  testkit::TempDir dir;
  Scenario sc = one_body(dir, samples::make_box_mesh(3, 3, 3, 0.1, 0.1, 0.1), testkit::linear_elastic_instance("rubber", 1e6, 0.3, 1000));
  sc.run.end_time = 0.02;
  sc.curves["press"] = table("press", {0.0, 0.005, 0.012}, {0.0, 1.0, 0.4});
  sc.boundaries.push_back(testkit::boundary("body", "zmin", solver::BoundaryType::fixed, {true, true, true}, "base"));
  BoundarySpec top = testkit::boundary("body", "zmax", solver::BoundaryType::displacement, {true, true, true}, "top");
  top.displacement = {2e-4, 0, -1e-3};
  top.curve = "press";
  sc.boundaries.push_back(top);
  const Model m = build_model(sc);
  ExplicitSolver s(m, sc.run, sc.damping);
  double worst = 0;
  std::size_t checked = 0;
  run_until(s, [&] {
    const double c = sc.curves["press"].at(s.time());
    for (std::size_t i = 0; i < 3 * m.num_nodes; ++i)
      if (m.constrained[i] == 2) {
        worst = std::max(worst, std::abs(s.displacement()[i] - m.constraint_velocity[i] * c));
        ++checked;
      }
    return false;
  });
  std::printf("displacement boundary: %zu dof-steps checked, largest |u - d c(t)| = %.3g m (of 1e-3 m)\n", checked, worst);
  EXPECT_GT(checked, 1000u);
  EXPECT_LE(worst, 1e-18);
}

// Quasi-static compression of a linear-elastic cube on rollers (small strain, lateral faces free):
// the top reaction is E eps A once the ramp is held and the motion has died out.
TEST(Loading, QuasiStaticCompressionReactionIsEEpsA) {
  testkit::TempDir dir;
  const double L = 0.1, E = 1e6, eps = 1e-4;
  Scenario sc = one_body(dir, samples::make_box_mesh(3, 3, 3, L, L, L), testkit::linear_elastic_instance("block", E, 0.3, 1000));
  sc.run.end_time = 1.0;
  sc.damping.alpha = 600;
  sc.curves["ramp"] = smooth_step("ramp", 0.0, 0.03);
  sc.boundaries.push_back(testkit::boundary("body", "zmin", solver::BoundaryType::fixed, {false, false, true}, "base"));
  sc.boundaries.push_back(testkit::boundary("body", "xmin", solver::BoundaryType::fixed, {true, false, false}, "symmetry_x"));
  sc.boundaries.push_back(testkit::boundary("body", "ymin", solver::BoundaryType::fixed, {false, true, false}, "symmetry_y"));
  BoundarySpec top = testkit::boundary("body", "zmax", solver::BoundaryType::displacement, {false, false, true}, "top");
  top.displacement = {0, 0, -eps * L};
  top.curve = "ramp";
  sc.boundaries.push_back(top);
  const Model m = build_model(sc);
  ExplicitSolver s(m, sc.run, sc.damping);
  run_until(s, [&] { return s.time() > 0.03 && s.energies().kinetic <= 1e-8 * s.energies().internal; });
  const double Rz = s.reactions().force[3 * 3 + 2], expected = -E * eps * L * L;
  std::printf("compression: t = %.4f s, kinetic/internal = %.2e, top reaction %.6f N vs -E eps A = %.6f N (%.3f %%), base %.6f N\n", s.time(),
              s.energies().kinetic / s.energies().internal, Rz, expected, 100 * (Rz / expected - 1), s.reactions().force[2]);
  EXPECT_LT(s.time(), sc.run.end_time);
  EXPECT_NEAR(Rz, expected, 0.01 * std::abs(expected));
  EXPECT_NEAR(s.reactions().force[2], -expected, 0.01 * std::abs(expected));  // the base pushes back
}

// Reaction balance: a cube on a fixed base under gravity, relaxed until kinetic energy <= 1e-12
// of the strain energy: the reactions sum to minus the body load m g, to 1e-6.
TEST(Loading, ReactionsBalanceTheBodyLoad) {
  testkit::TempDir dir;
  Scenario sc = one_body(dir, samples::make_box_mesh(2, 2, 2, 0.1, 0.1, 0.1), testkit::linear_elastic_instance("block", 2e5, 0.3, 1000));
  sc.run.end_time = 5.0;
  sc.run.gravity = {1.0, -2.0, -9.81};
  sc.run.gravity_curve = "ramp";
  sc.damping.alpha = 300;
  sc.curves["ramp"] = smooth_step("ramp", 0.0, 0.05);
  sc.boundaries.push_back(testkit::boundary("body", "zmin", solver::BoundaryType::fixed, {true, true, true}, "base"));
  const Model m = build_model(sc);
  double mass = 0;
  for (double mi : m.mass) mass += mi;
  ExplicitSolver s(m, sc.run, sc.damping);
  run_until(s, [&] { return s.time() > 0.05 && s.energies().kinetic <= 1e-12 * s.energies().internal; });
  double worst = 0;
  for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(s.reactions().force[static_cast<std::size_t>(c)] + mass * sc.run.gravity[c]));
  const double load = mass * std::sqrt(1 + 4 + 9.81 * 9.81);
  std::printf("reaction balance: t = %.3f s, reaction (%.9f, %.9f, %.9f) N vs -m g (%.9f, %.9f, %.9f) N, worst %.2e of |m g|\n", s.time(),
              s.reactions().force[0], s.reactions().force[1], s.reactions().force[2], -mass * 1.0, mass * 2.0, mass * 9.81, worst / load);
  EXPECT_LT(s.time(), sc.run.end_time);
  EXPECT_LE(worst, 1e-6 * load);
}

namespace {

// A bar along x (fixed at x = 0, every node held in y and z: one-dimensional with nu = 0) set
// moving in its first axial mode, v(x) = V sin(pi x / 2L). Returns the decay rate of the
// mechanical energy (a least-squares line through ln E over whole periods) and the mode's angular
// frequency from the tip displacement's zero crossings.
struct Decay {
  double rate, omega;
};
Decay bar_first_mode_decay(double alpha, double beta) {
  testkit::TempDir dir;
  const double L = 1.0;
  Scenario sc = one_body(dir, samples::make_box_mesh(24, 1, 1, L, 0.05, 0.05), testkit::linear_elastic_instance("bar", 1e6, 0.0, 1000));
  sc.run.end_time = 0.8;  // about six periods
  sc.damping = {alpha, beta};
  sc.boundaries.push_back(testkit::boundary("body", "xmin", solver::BoundaryType::fixed, {true, true, true}, "root"));
  BoundarySpec lateral;
  lateral.body = "body", lateral.box = std::array<Vec3, 2>{Vec3{-1, -1, -1}, Vec3{2, 1, 1}}, lateral.type = BoundaryType::fixed;
  lateral.components = {false, true, true}, lateral.name = "lateral";
  sc.boundaries.push_back(lateral);
  Model m = build_model(sc);
  for (std::size_t i = 0; i < m.num_nodes; ++i) m.initial_velocity[3 * i] = 0.1 * std::sin(kPi * m.X[3 * i] / (2 * L));
  std::size_t tip = 0;
  for (std::size_t i = 0; i < m.num_nodes; ++i)
    if (m.X[3 * i] > m.X[3 * tip]) tip = i;
  ExplicitSolver s(m, sc.run, sc.damping);
  std::vector<double> t, lnE, crossings;
  double prev_u = 0;
  run_until(s, [&] {
    const double u = s.displacement()[3 * tip];
    if (s.step_index() > 0 && ((prev_u > 0) != (u > 0)))  // linear interpolation of the crossing
      crossings.push_back(s.time() - s.last_step() * u / (u - prev_u));
    prev_u = u;
    t.push_back(s.time());
    lnE.push_back(std::log(s.energies().kinetic + s.energies().internal));
    return false;
  });
  // Omega from the crossings (half a period apart); the fit over whole half periods from the
  // first crossing to the last, where the energy's own oscillation (period T/2) averages out.
  const double half_period = (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  double st = 0, sy = 0, stt = 0, sty = 0, n = 0;
  for (std::size_t k = 0; k < t.size(); ++k)
    if (t[k] >= crossings.front() && t[k] <= crossings.back()) st += t[k], sy += lnE[k], stt += t[k] * t[k], sty += t[k] * lnE[k], ++n;
  const double slope = (n * sty - st * sy) / (n * stt - st * st);
  return {-slope, kPi / half_period};
}

}  // namespace

// Rayleigh damping against the analytic decay of a single mode: with A = alpha M + beta K each
// mode's amplitude decays as exp(-zeta omega t) with 2 zeta omega = alpha + beta omega^2, so its
// energy decays at the rate alpha + beta omega^2. alpha alone and beta alone, within 2 %.
TEST(Loading, RayleighDampingDecaysASingleModeAtTheAnalyticRate) {
  const Decay a = bar_first_mode_decay(2.0, 0.0);
  std::printf("alpha = 2 /s: energy decay rate %.5f /s vs alpha = 2 (%.2f %%), omega %.3f rad/s\n", a.rate, 100 * (a.rate / 2.0 - 1), a.omega);
  EXPECT_NEAR(a.rate, 2.0, 0.02 * 2.0);
  const double beta = 2.0 / (a.omega * a.omega);  // about the same decay through the stiffness term
  const Decay b = bar_first_mode_decay(0.0, beta);
  const double expected = beta * b.omega * b.omega;
  std::printf("beta = %.4g s: energy decay rate %.5f /s vs beta omega^2 = %.5f /s (%.2f %%)\n", beta, b.rate, expected,
              100 * (b.rate / expected - 1));
  EXPECT_NEAR(b.rate, expected, 0.02 * expected);
  const Decay none = bar_first_mode_decay(0.0, 0.0);
  std::printf("undamped: energy decay rate %.2e /s\n", none.rate);
  EXPECT_LT(std::abs(none.rate), 1e-3);
}

// Rotation: the same cube (hgo with constant fibres) with its base fixed, under gravity, and the
// cube rotated about an oblique axis under the rotated gravity: the second solution is the first
// rotated, displacements within 1e-9 relative, so the fibres turned with the body.
TEST(Loading, RotatedBodyUnderRotatedLoadsGivesTheRotatedSolution) {
  testkit::TempDir dir;
  const MaterialInstance tissue{
      "tissue",
      "hgo",
      {{{"c1", 1e4}, {"k1", 2e4}, {"k2", 5.0}, {"k", 2e5}, {"density", 1000}}, {{"fibres", {Vec3{0.8, 0.6, 0}, Vec3{0, 0.6, 0.8}}}}}};
  Scenario a = one_body(dir, samples::make_box_mesh(3, 3, 3, 0.1, 0.1, 0.1), tissue);
  a.run.end_time = 0.01;
  a.run.gravity = {10, -20, -150};
  a.boundaries.push_back(testkit::boundary("body", "zmin", solver::BoundaryType::fixed, {true, true, true}, "base"));
  Scenario b = a;
  BodySpec& body = b.bodies[0];
  const double th = 40 * kPi / 180, n = std::sqrt(14.0), x = 1 / n, y = 2 / n, z = 3 / n, c = std::cos(th), s = std::sin(th), C = 1 - c;
  body.rotation = {Vec3{c + x * x * C, x * y * C - z * s, x * z * C + y * s}, Vec3{y * x * C + z * s, c + y * y * C, y * z * C - x * s},
                   Vec3{z * x * C - y * s, z * y * C + x * s, c + z * z * C}};
  body.rotate_about = {0.05, 0.02, -0.01};
  body.rotated = true;
  auto R = [&](const Vec3& v) {
    Vec3 out{};
    for (int i = 0; i < 3; ++i) out[i] = body.rotation[i][0] * v[0] + body.rotation[i][1] * v[1] + body.rotation[i][2] * v[2];
    return out;
  };
  b.run.gravity = R(a.run.gravity);
  const Model ma = build_model(a), mb = build_model(b);
  a.run.time_step = b.run.time_step = 0.8 * ExplicitSolver(ma, a.run, a.damping).time_step();  // one step for both
  ExplicitSolver sa(ma, a.run, a.damping), sb(mb, b.run, b.damping);
  const std::size_t steps = run_until(sa, [] { return false; });
  EXPECT_EQ(run_until(sb, [] { return false; }), steps);
  double worst = 0, largest = 0;
  for (std::size_t i = 0; i < ma.num_nodes; ++i) {
    const auto ia = static_cast<std::size_t>(ma.node_of_input[i]), ib = static_cast<std::size_t>(mb.node_of_input[i]);
    const Vec3 ua{sa.displacement()[3 * ia], sa.displacement()[3 * ia + 1], sa.displacement()[3 * ia + 2]};
    const Vec3 expected = R(ua);
    for (int k = 0; k < 3; ++k) {
      worst = std::max(worst, std::abs(sb.displacement()[3 * ib + static_cast<std::size_t>(k)] - expected[k]));
      largest = std::max(largest, std::abs(ua[k]));
    }
  }
  std::printf("rotation: %zu steps, largest displacement %.4g m, largest |u_rotated - R u| = %.3g m (%.2e relative)\n", steps, largest, worst,
              worst / largest);
  EXPECT_GT(largest, 1e-4);
  EXPECT_LE(worst, 1e-9 * largest);
}

// Follower pressure: a thick-walled cylinder (a quarter, plane strain, small strain, nu = 0.3)
// under a ramped internal pressure, held until at rest: the radial displacement of the inner and
// outer walls against Lame's solution u(r) = (1 + nu) p a^2 / (E (b^2 - a^2)) ((1 - 2 nu) r + b^2 / r).
TEST(Loading, PressurisedThickCylinderMatchesLame) {
  testkit::TempDir dir;
  const double a = 0.05, b = 0.1, E = 1e6, nu = 0.3, p = 100.0;
  TetMesh mesh = samples::make_box_mesh(8, 16, 1, 1.0, 1.0, 0.01);  // (radius fraction, angle fraction, z)
  for (auto& X : mesh.nodes) {
    const double r = a + (b - a) * X[0], phi = 0.5 * kPi * X[1];
    X = {r * std::cos(phi), r * std::sin(phi), X[2]};
  }
  Scenario sc = one_body(dir, mesh, testkit::linear_elastic_instance("steel", E, nu, 1000));
  sc.run.end_time = 2.0;
  sc.damping.alpha = 400;
  sc.curves["ramp"] = smooth_step("ramp", 0.0, 0.05);
  sc.boundaries.push_back(testkit::boundary("body", "ymin", solver::BoundaryType::fixed, {false, true, false}, "cut_y"));  // phi = 0: the y = 0 plane
  sc.boundaries.push_back(testkit::boundary("body", "ymax", solver::BoundaryType::fixed, {true, false, false}, "cut_x"));  // phi = 90 deg: x = 0
  sc.boundaries.push_back(testkit::boundary("body", "zmin", solver::BoundaryType::fixed, {false, false, true}, "plane_strain_0"));
  sc.boundaries.push_back(testkit::boundary("body", "zmax", solver::BoundaryType::fixed, {false, false, true}, "plane_strain_1"));
  sc.loads.push_back(LoadSpec{"body", "xmin", p, "ramp"});  // the inner wall r = a
  const Model m = build_model(sc);
  ExplicitSolver s(m, sc.run, sc.damping);
  run_until(s, [&] { return s.time() > 0.05 && s.energies().kinetic <= 1e-10 * s.energies().internal; });
  auto lame = [&](double r) { return (1 + nu) * p * a * a / (E * (b * b - a * a)) * ((1 - 2 * nu) * r + b * b / r); };
  double sum[2] = {0, 0}, count[2] = {0, 0};
  for (std::size_t i = 0; i < m.num_nodes; ++i) {
    const double X = m.X[3 * i], Y = m.X[3 * i + 1], r = std::hypot(X, Y);
    const int wall = std::abs(r - a) < 1e-9 ? 0 : std::abs(r - b) < 1e-9 ? 1 : -1;
    if (wall < 0) continue;
    sum[wall] += (s.displacement()[3 * i] * X + s.displacement()[3 * i + 1] * Y) / r;
    count[wall] += 1;
  }
  const double ua = sum[0] / count[0], ub = sum[1] / count[1];
  std::printf("thick cylinder: t = %.3f s; radial displacement inner %.6e m vs Lame %.6e (%.2f %%), outer %.6e vs %.6e (%.2f %%)\n", s.time(), ua,
              lame(a), 100 * (ua / lame(a) - 1), ub, lame(b), 100 * (ub / lame(b) - 1));
  EXPECT_LT(s.time(), sc.run.end_time);
  EXPECT_NEAR(ua, lame(a), 0.02 * lame(a));
  EXPECT_NEAR(ub, lame(b), 0.02 * lame(b));
}
