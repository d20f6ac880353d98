// solver/patch: a linear displacement field on an irregular mesh gives the exact constant
// stress. For constant P the assembled internal force of node i is
//   f_i = -sum_e V_e P grad N_i = -P \oint N_i N dA = -P sum_{boundary triangles t of i} (A_t / 3) N_t
// (divergence theorem), zero at interior nodes: every node is checked against that, for standard
// and average-nodal-pressure tets.
#include <gtest/gtest.h>

#include "material_kit.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/internal_force.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/model_build.hpp"

using namespace tactus;
using namespace tactus::solver;
using namespace tactus::testkit;

namespace {

void patch_test(const Material& material) {
  TetMesh mesh = samples::make_box_mesh(4, 3, 5, 0.04, 0.03, 0.05);
  samples::perturb_interior_nodes(mesh, 0.01, 0.3, 2024);  // irregular: up to 30 % of a cell
  samples::shuffle_numbering(mesh, 7);                     // and numbered without order
  const Model model = build_model(mesh, material);
  Mat3 A;  // a general (non-symmetric) displacement gradient
  A << 0.02, -0.01, 0.015, 0.005, -0.03, 0.01, -0.012, 0.008, 0.025;
  std::vector<double> u(3 * model.num_nodes), v(3 * model.num_nodes, 0.0), f(3 * model.num_nodes);
  for (std::size_t i = 0; i < model.num_nodes; ++i)
    for (int r = 0; r < 3; ++r) u[3 * i + r] = A(r, 0) * model.X[3 * i] + A(r, 1) * model.X[3 * i + 1] + A(r, 2) * model.X[3 * i + 2] + 1e-3;
  InternalForces forces(model, 0.0, 2);
  const StressPassResult pass = forces.compute(u.data(), v.data(), f.data());

  const Mat3 F = Mat3::Identity() + A;
  const StressPoint exact = material.evaluate(F);
  const double volume = 0.04 * 0.03 * 0.05;
  EXPECT_NEAR(pass.strain_energy, exact.W * volume, 1e-10 * exact.W * volume);

  std::vector<Vec3d> expected(mesh.nodes.size(), Vec3d::Zero());
  for (const auto& t : mesh.triangles) {
    const Vec3d a(mesh.nodes[t[0]].data()), b(mesh.nodes[t[1]].data()), c(mesh.nodes[t[2]].data());
    const Vec3d area_normal = 0.5 * (b - a).cross(c - a);  // outward, |.| = area
    for (int v3 : t) expected[static_cast<std::size_t>(v3)] -= exact.P * area_normal / 3.0;
  }
  const double scale = exact.P.norm() * 1e-4;  // |P| times a cell face area
  double worst = 0;
  for (std::size_t i = 0; i < mesh.nodes.size(); ++i) {
    const std::size_t k = static_cast<std::size_t>(model.node_of_input[i]);
    const Vec3d fi(f[3 * k], f[3 * k + 1], f[3 * k + 2]);
    worst = std::max(worst, (fi - expected[i]).norm());
  }
  // Round-off only (sums of ~20 terms of size `scale`): 1e-10 relative.
  EXPECT_LE(worst, 1e-10 * scale) << material.type_name();
}

}  // namespace

TEST(Patch, ConstantStressNeoHookean) { patch_test(neo_hookean(3000.0, 50000.0, 1000.0)); }
TEST(Patch, ConstantStressLinearElastic) { patch_test(linear_elastic(1e9, 0.3, 2000)); }
TEST(Patch, ConstantStressHgo) { patch_test(paper_hgo(1e8, "standard")); }
// ANP tets: a uniform J gives every node the same J, so the patch test stays exact (forces and
// the energy, whose volumetric part is then sum_a V_a U(J) = V U(J)).
TEST(Patch, ConstantStressNeoHookeanAnp) { patch_test(neo_hookean(3000.0, 50000.0, 1000.0, "anp")); }
TEST(Patch, ConstantStressHgoAnp) {
  ASSERT_TRUE(paper_hgo().anp());  // k / 2 c1 = 4,900: ANP by default
  patch_test(paper_hgo());
}
