// Results independent of the thread count (issue: "runs that survive interruption", item 3): an
// ANP hgo block of 9,216 tets (three stress partitions) thrown with a spin onto a rigid plane with
// friction under gravity, 300 steps on 1, 2 and 3 threads. Oracle: the 1-thread run itself;
// displacements, velocities and every energy must be the same bits (memcmp), not merely close.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>

#include "material_kit.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/contact.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/internal_force.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/model_build.hpp"

using namespace tactus;
using namespace tactus::solver;

namespace {

struct Final {
  std::vector<double> u, v;
  Energies energies;
  double time = 0;
};

Final run_on(int threads) {
  const TetMesh mesh = samples::make_box_mesh(16, 16, 6, 0.032, 0.032, 0.012);
  Model model = build_model(mesh, testkit::paper_hgo(1e7, "anp"));
  for (std::size_t i = 0; i < model.num_nodes; ++i) {  // falling at 1 m/s, spinning about z
    const double x = model.X[3 * i] - 0.016, y = model.X[3 * i + 1] - 0.016;
    model.initial_velocity[3 * i] = -20.0 * y, model.initial_velocity[3 * i + 1] = 20.0 * x, model.initial_velocity[3 * i + 2] = -1.0;
    model.X[3 * i + 2] += 1e-4;  // just above the plane
  }
  ContactPair plane;
  plane.name = "floor";
  plane.friction = 0.3;
  set_rigid_plane(plane, {0, 0, 0}, {0, 0, 1});
  set_slave_surface(plane, model, surface_triangles(model, 15));  // zmin
  model.contact_pairs.push_back(plane);
  RunSpec run;
  run.end_time = 1e9;
  run.threads = threads;
  run.gravity = {0, 0, -9.81};
  ExplicitSolver solver(model, run, DampingSpec{});
  for (int n = 0; n < 300; ++n) {
    solver.advance_velocity();
    solver.advance_position();
  }
  solver.advance_velocity();
  return {solver.displacement(), solver.velocity_at_step(), solver.energies(), solver.time()};
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

}  // namespace

TEST(Determinism, SameBitsOnOneTwoAndThreeThreads) {
  ASSERT_GE(9216u, 2 * kAtomTets + 1);  // several atoms
  const Final one = run_on(1);
  std::printf("1 thread: t = %.6e s, kinetic %.17g J, internal %.17g J, contact work %.17g J\n", one.time, one.energies.kinetic,
              one.energies.internal, one.energies.contact_work());
  EXPECT_GT(one.energies.contact_work(), 0.0);  // the plane was hit
  for (int threads : {2, 3}) {
    const Final other = run_on(threads);
    std::size_t differ = 0;
    for (std::size_t i = 0; i < one.u.size(); ++i) differ += std::memcmp(&one.u[i], &other.u[i], sizeof(double)) != 0;
    std::printf("%d threads: %zu of %zu displacement components differ in any bit; kinetic %.17g, internal %.17g, contact work %.17g\n", threads,
                differ, one.u.size(), other.energies.kinetic, other.energies.internal, other.energies.contact_work());
    EXPECT_EQ(one.time, other.time);
    EXPECT_TRUE(same_bits(one.u, other.u));
    EXPECT_TRUE(same_bits(one.v, other.v));
    EXPECT_EQ(std::memcmp(&one.energies, &other.energies, sizeof(Energies)), 0);
  }
}
