// solver/contact: Hertz's pressure distribution. An elastic sphere (quarter model on rollers, its
// flat top pushed down by a ramped displacement and held) pressed frictionless on a rigid plane
// (node to surface) and on a deformable block of the same material (mortar), at rest: the contact
// radius, the central pressure and the profile p(r) against Hertz's for the force it carries, on
// a graded mesh, and again with the element size near the contact halved.
#include <gtest/gtest.h>

#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "gmsh_kit.hpp"
#include "scenario_kit.hpp"
#include "tactus/core/gmsh_session.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/model_build.hpp"
#include "temp_dir.hpp"

using namespace tactus;
using namespace tactus::solver;

namespace {

constexpr double kRadius = 0.01;  // sphere radius R, m
// The contact radius aimed at. Hertz is a small-strain theory and linear_elastic is St Venant-
// Kirchhoff, which softens by ~1.5 eps in compression: at a / R = 0.11 the strain under the
// pole, p0 / E ~ 0.7 a / R ~ 8 %, cost p0 12 % (measured, the same on both meshes). At a / R =
// 0.03 it is ~2 %.
constexpr double kContactRadius = 0.03 * kRadius;
constexpr double kBlock = 0.008;  // the quarter block's half-width and depth (53 a wide)
constexpr double kE = 1e6, kNu = 0.3, kDensity = 1000;

// The lower quarter of a sphere of radius R whose pole touches z = gap: x, y >= 0, z <= gap + R,
// graded from h at the pole (within 1.5 a) to 2.5 mm. Faces: "xmin", "ymin", "zmax" (the flat top)
// and "surface" (the spherical one, group 20).
TetMesh quarter_sphere(double gap, double h) {
  GmshSession session;
  gmsh::model::add("quarter_sphere");
  const int ball = gmsh::model::occ::addSphere(0, 0, gap + kRadius, kRadius);
  const int box = gmsh::model::occ::addBox(0, 0, gap - 1e-3, 2 * kRadius, 2 * kRadius, kRadius + 1e-3);
  gmsh::vectorpair out;
  std::vector<gmsh::vectorpair> map;
  gmsh::model::occ::intersect({{3, ball}}, {{3, box}}, out, map);
  gmsh::model::occ::synchronize();
  const int vol = out.at(0).second;
  gmsh::model::addPhysicalGroup(3, {vol}, 1);
  gmsh::model::setPhysicalName(3, 1, "sphere");
  const double lo[3] = {0, 0, gap - 1e-3}, hi[3] = {2 * kRadius, 2 * kRadius, gap + kRadius};
  const std::vector<int> curved = testkit::tag_box_plane_faces(vol, lo, hi);
  gmsh::model::addPhysicalGroup(2, curved, 20);
  gmsh::model::setPhysicalName(2, 20, "surface");
  const double pole[3] = {0, 0, gap};
  testkit::graded_size_field(pole, h, 2.5e-3, 1.5 * kContactRadius, 0.3);
  return testkit::generate_tet_mesh("quarter_sphere");
}

// The quarter block [0, B] x [0, B] x [-B, 0], graded from h at the origin like the sphere.
TetMesh quarter_block(double h) {
  GmshSession session;
  gmsh::model::add("quarter_block");
  const int vol = gmsh::model::occ::addBox(0, 0, -kBlock, kBlock, kBlock, kBlock);
  gmsh::model::occ::synchronize();
  gmsh::model::addPhysicalGroup(3, {vol}, 1);
  gmsh::model::setPhysicalName(3, 1, "block");
  const double lo[3] = {0, 0, -kBlock}, hi[3] = {kBlock, kBlock, 0};
  testkit::tag_box_plane_faces(vol, lo, hi);
  const double centre[3] = {0, 0, 0};
  testkit::graded_size_field(centre, h, 2.5e-3, 1.5 * kContactRadius, 0.3);
  return testkit::generate_tet_mesh("quarter_block");
}

struct HertzOutcome {
  std::size_t tets = 0, steps = 0, contact_nodes = 0;
  double force = 0;                  // the whole sphere's contact force, N (4 x the quarter's)
  double a_hertz = 0, p0_hertz = 0;  // Hertz's contact radius and central pressure for that force
  double a = 0, p0 = 0;              // measured: the profile's fit (below)
  double pole = 0;                   // the pole node's pressure (printed: one node's lumped area)
  double profile_rms = 0;            // RMS over the slave nodes within 1.2 a_hertz of p - p_hertz(r), / p0_hertz
  double kinetic_ratio = 0, added_mass = 0;
};

// The press, at rest; `on_block`: on the deformable block (mortar) instead of the rigid plane.
HertzOutcome hertz_press(double h, bool on_block) {
  testkit::TempDir dir;
  Scenario sc;
  sc.file = dir.path() / "hertz.toml";
  const double c = std::sqrt(kE * (1 - kNu) / ((1 + kNu) * (1 - 2 * kNu) * kDensity));  // P-wave speed
  const double transit = kRadius / c;
  sc.run.end_time = 400 * transit;
  // Quasi-static: mass only matters for how many steps the rest takes. The small tets near the
  // contact (a few 1e-3 of the mass) get mass up to the step of 0.5 mm tets.
  sc.run.minimum_time_step = 0.6 * 0.5e-3 / (2.5 * c);
  sc.run.added_mass_limit = 0.5;
  sc.damping.alpha = 0.5 * c / kRadius;  // about the lowest mode's critical damping
  sc.materials["m"] = testkit::linear_elastic_instance("m", kE, kNu, kDensity);
  const double gap = 1e-7;
  sc.bodies.push_back(testkit::body_from_mesh(dir, "sphere", quarter_sphere(on_block ? gap : 0.0, h), "m"));
  if (on_block) sc.bodies.push_back(testkit::body_from_mesh(dir, "block", quarter_block(h), "m"));
  sc.curves["ramp"] = CurveSpec{"ramp", {}, {}, true, 0.0, 60 * transit};
  for (const auto& body : sc.bodies) {  // rollers on the two symmetry planes
    sc.boundaries.push_back(testkit::boundary(body.name, "xmin", solver::BoundaryType::fixed, {true, false, false}, body.name + "_x"));
    sc.boundaries.push_back(testkit::boundary(body.name, "ymin", solver::BoundaryType::fixed, {false, true, false}, body.name + "_y"));
  }
  if (on_block) sc.boundaries.push_back(testkit::boundary("block", "zmin", solver::BoundaryType::fixed, {false, false, true}, "base"));
  // Hertz's approach for the contact radius a is a^2 / R (with the sphere's own compression away
  // from the contact, on the block too, about that).
  BoundarySpec top = testkit::boundary("sphere", "zmax", solver::BoundaryType::fixed, {false, false, true}, "top");
  top.type = BoundaryType::displacement, top.displacement = {0, 0, -kContactRadius * kContactRadius / kRadius - gap}, top.curve = "ramp";
  sc.boundaries.push_back(top);
  ContactSpec contact;
  contact.slave_body = "sphere", contact.slave_surface = "surface";
  if (on_block)
    contact.master_body = "block", contact.master_surface = "zmax";
  else
    contact.plane = std::array<Vec3, 2>{Vec3{0, 0, 0}, Vec3{0, 0, 1}};
  sc.contacts.push_back(contact);
  sc.contact_solver.tolerance = 1e-10;
  sc.contact_solver.max_iterations = 2000;
  const Model m = build_model(sc);
  ExplicitSolver s(m, sc.run, sc.damping);
  testkit::run_to_rest(s, 80 * transit, 1e-8);
  HertzOutcome o;
  o.tets = m.num_elements, o.steps = s.step_index();
  o.kinetic_ratio = s.energies().kinetic / s.energies().internal;
  for (double dm : s.added_mass()) o.added_mass += dm;
  const ContactRows& rows = s.contact().rows();
  std::vector<double> radius(rows.size()), pressure(rows.size());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const double rn = rows.reaction[3 * k] * rows.normal[3 * k] + rows.reaction[3 * k + 1] * rows.normal[3 * k + 1] +
                      rows.reaction[3 * k + 2] * rows.normal[3 * k + 2];
    const std::size_t node = static_cast<std::size_t>(rows.slave(k));
    const double x = m.X[3 * node] + s.displacement()[3 * node], y = m.X[3 * node + 1] + s.displacement()[3 * node + 1];
    radius[k] = std::hypot(x, y), pressure[k] = rn / rows.area[k];
    o.force += 4 * rn;
    if (rn > 0) ++o.contact_nodes;
  }
  const double E_star = (on_block ? 0.5 : 1.0) * kE / (1 - kNu * kNu);
  o.a_hertz = std::cbrt(3 * o.force * kRadius / (4 * E_star));
  o.p0_hertz = 3 * o.force / (2 * M_PI * o.a_hertz * o.a_hertz);
  // p^2 = p0^2 (1 - r^2 / a^2) is linear in r^2: least squares over the nodes inside 0.8 a_hertz
  // (away from the edge, where one element smears the square root) gives the central pressure and
  // the radius the profile closes at. (The pole node alone is off by up to 5 % either way as the
  // triangles around it change with a / R: it lies where the two symmetry planes cut the surface.)
  double s0 = 0, s1 = 0, s2 = 0, t0 = 0, t1 = 0, pole = 1e300, sum = 0;
  int count = 0;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const double r2 = radius[k] * radius[k], p = std::max(0.0, pressure[k]);
    if (radius[k] < pole) pole = radius[k], o.pole = p;
    if (radius[k] < 0.8 * o.a_hertz) s0 += 1, s1 += r2, s2 += r2 * r2, t0 += p * p, t1 += p * p * r2;
    if (radius[k] < 1.2 * o.a_hertz) {
      const double ph = o.p0_hertz * std::sqrt(std::max(0.0, 1 - r2 / (o.a_hertz * o.a_hertz)));
      sum += (p - ph) * (p - ph), ++count;
    }
  }
  const double slope = (s0 * t1 - s1 * t0) / (s0 * s2 - s1 * s1), intercept = (t0 - slope * s1) / s0;
  o.a = std::sqrt(-intercept / slope), o.p0 = std::sqrt(intercept);
  o.profile_rms = std::sqrt(sum / count) / o.p0_hertz;
  std::printf(
      "hertz, sphere on a %s, h = %.3f mm at the contact (a_hertz / h = %.1f): %zu tets, %zu steps, added mass %.2e kg, kinetic/strain %.1e; "
      "force %.4f N, %zu nodes pressed; contact radius %.4f mm (Hertz %.4f, %+.2f %%, a/R = %.3f), central pressure %.1f Pa (Hertz %.1f, "
      "%+.2f %%; the pole node %+.2f %%), profile RMS %.2f %% of p0 over %d nodes\n",
      on_block ? "deformable block (mortar)" : "rigid plane (node to surface)", h * 1e3, o.a_hertz / h, o.tets, o.steps, o.added_mass,
      o.kinetic_ratio, o.force, o.contact_nodes, o.a * 1e3, o.a_hertz * 1e3, 100 * (o.a / o.a_hertz - 1), o.a_hertz / kRadius, o.p0, o.p0_hertz,
      100 * (o.p0 / o.p0_hertz - 1), 100 * (o.pole / o.p0_hertz - 1), 100 * o.profile_rms, count);
  return o;
}

}  // namespace

// Oracle: Hertz. For the force P the sphere carries, a = (3 P R / (4 E*))^(1/3) and
// p(r) = p0 sqrt(1 - r^2 / a^2), p0 = 3 P / (2 pi a^2); E* = E / (1 - nu^2) on a rigid plane and
// half that on a block of the same material (both half-spaces: the block is ~50 a wide and ~25 a deep,
// a / R ~ 0.03). With 10 elements across a: radius and p0 within 5 %, the profile within 5 % of p0
// (RMS over the nodes within 1.2 a); halving the size near the contact cuts that error >= 1.3x.
TEST(Contact, HertzPressureDistributionOnARigidPlaneAndABlock) {
  for (const bool on_block : {false, true}) {
    const HertzOutcome coarse = hertz_press(0.1 * kContactRadius, on_block);
    const HertzOutcome fine = hertz_press(0.05 * kContactRadius, on_block);
    std::printf("hertz, %s: profile RMS %.2f %% -> %.2f %% of p0 when h is halved (ratio %.2f)\n", on_block ? "block" : "plane",
                100 * coarse.profile_rms, 100 * fine.profile_rms, coarse.profile_rms / fine.profile_rms);
    for (const HertzOutcome* o : {&coarse, &fine}) {
      EXPECT_LE(o->kinetic_ratio, 1e-6);
      EXPECT_LE(o->a_hertz / kRadius, 0.15);
      EXPECT_NEAR(o->a / o->a_hertz, 1.0, 0.05);
      EXPECT_NEAR(o->p0 / o->p0_hertz, 1.0, 0.05);
      EXPECT_LE(o->profile_rms, 0.05);
    }
    EXPECT_GE(coarse.profile_rms, 1.3 * fine.profile_rms);
  }
}
