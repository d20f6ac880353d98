// The grasp over MPI ranks steps as one process does (issue: MPI, "Rank-count independence"):
// the synthetic finger of the grasp tests (finger_kit.hpp: soft tissue round three rigid bones
// driven by their joints) closing on a rigid handle under the grasp controller, skin on handle by
// mortar with friction, with adaptive dynamic relaxation and its residual measured every step.
// Every sum these add over the dofs (the energy audit, the relaxation's stiffness, inertia and
// out-of-balance force) is taken in fixed chunks each summed by one rank (owned-node stepping).
// The same model is stepped twice in this process, by ExplicitSolver alone (one thread) and with
// the stress pass spread over the ranks of this mpiexec, in lockstep. Oracle: the one-process run.
// After every step the state is gathered and every displacement and half-step velocity component,
// the energies, the relaxation's damping and residual and the grip force must be the same bits on
// every rank. Run by CTest on 1 to 4 ranks.
#include <mpi.h>

#include <cstdio>
#include <cstring>
#include <vector>

#include "finger_kit.hpp"
#include "tactus/solver/decomposition.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/model_build.hpp"
#include "tactus/solver/ranks.hpp"

using namespace tactus;
using namespace tactus::solver;
using namespace tactus::testkit;

namespace {

bool same(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}
bool same(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

// The finger over the handle as test_grasp.cpp's grasp_scenario, adaptive relaxation on.
Scenario grasp_scenario(const TempDir& dir) {
  Scenario sc;
  sc.file = dir.path() / "grasp.toml";
  add_finger(sc, dir);
  BodySpec handle = body_from_mesh(dir, "handle", cylinder_mesh(0.010, 0.030, 0.040, -0.012, 24, 4), "bone");
  handle.rigid_velocity = Vec3{0, 0, 0}, handle.rigid_angular_velocity = Vec3{0, 0, 0};
  sc.bodies.push_back(handle);
  ContactSpec c;
  c.slave_body = "finger", c.slave_surface = "surface", c.master_body = "handle", c.master_surface = "surface", c.friction = 0.3;
  sc.contacts.push_back(c);
  sc.grasp.handle = "handle";
  sc.grasp.target_force = 50;
  sc.grasp.ramp_time = 0.05;
  sc.grasp.max_torque = 5;
  sc.grasp.gain_p = 0.01;
  sc.grasp.gain_i = 3;
  sc.run.end_time = 0.03;
  sc.run.threads = 1;
  sc.damping.alpha = 0;
  sc.damping.adaptive = true;
  sc.damping.residual_tolerance = 2e-3;
  sc.damping.residual_after = sc.grasp.ramp_time;
  return sc;
}

}  // namespace

int main(int argc, char** argv) {
  int provided = 0, rank = 0, ranks = 1;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  int failures = 0;
  try {
    TempDir dir;
    const Scenario sc = grasp_scenario(dir);
    const Model model = build_model(sc);
    const Decomposition d = decompose(model, ranks);
    RankStressPass shared(model, d, MPI_COMM_WORLD, sc.damping.beta, 1);
    ExplicitSolver one(model, sc.run, sc.damping), on_ranks(model, sc.run, sc.damping, &shared);
    std::size_t steps = 0, contact_steps = 0, first_differing = 0;
    int differ = 0;
    while (true) {
      one.advance_velocity(), on_ranks.advance_velocity();
      on_ranks.gather_state();
      const bool step_same = same(one.displacement(), on_ranks.displacement()) && same(one.half_step_velocity(), on_ranks.half_step_velocity()) &&
                             same(one.energies().kinetic, on_ranks.energies().kinetic) &&
                             same(one.energies().balance_error(), on_ranks.energies().balance_error()) &&
                             same(one.relaxation().alpha(), on_ranks.relaxation().alpha()) &&
                             same(one.relaxation().relative_residual(), on_ranks.relaxation().relative_residual()) &&
                             same(one.joint_drive()->grip_force(), on_ranks.joint_drive()->grip_force());
      if (!step_same && !differ) differ = 1, first_differing = one.step_index();
      contact_steps += one.contact_report().normal_force > 0;
      if (one.finished() || one.relaxed()) break;
      one.advance_position(), on_ranks.advance_position();
      ++steps;
    }
    int all_differ = 0;
    MPI_Allreduce(&differ, &all_differ, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
    if (rank == 0) {
      std::printf(
          "finger grasping a handle, %zu tets, %d rank(s), %zu atoms: %zu steps, %zu in contact, grip %.4f N, adaptive alpha %.3f /s, "
          "residual %.3e; %d rank(s) differ from the one-process run in any bit of u, v, the energies, the relaxation or the grip",
          model.num_elements, ranks, d.atom_rank.size(), steps, contact_steps, one.joint_drive()->grip_force(), one.relaxation().alpha(),
          one.relaxation().relative_residual(), all_differ);
      if (differ) std::printf(" (rank 0 first at step %zu)", first_differing);
      std::printf("\nowned-node stepping %s: rank 0 integrates %zu of %zu nodes and sends %zu doubles after each update\n",
                  on_ranks.owned_node_stepping() ? "on" : "off", shared.integrated_nodes(), model.num_nodes, shared.ghost_doubles());
    }
    const bool stepping_right = on_ranks.owned_node_stepping() == (ranks > 1);
    if (rank == 0 && !stepping_right) std::printf("FAIL: owned-node stepping should be on over 2 ranks or more, off on one\n");
    if (rank == 0 && contact_steps < 20) std::printf("FAIL: the finger should press on the handle for 20 steps or more\n");
    failures = all_differ + (contact_steps < 20 ? 1 : 0) + (stepping_right ? 0 : 1);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tactus_test_rank_grasp: %s\n", e.what());
    MPI_Abort(MPI_COMM_WORLD, 2);
  }
  MPI_Finalize();
  return failures == 0 ? 0 : 1;
}
