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
// every rank. Then the crushed-tissue message on ranks (crushed, below). Run by CTest on 1 to 4
// ranks.
#include <mpi.h>

#include <cstdio>
#include <string>
#include <vector>

#include "finger_kit.hpp"
#include "rank_lockstep.hpp"
#include "tactus/core/error.hpp"
#include "tactus/solver/decomposition.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/model_build.hpp"
#include "tactus/solver/ranks.hpp"

using namespace tactus;
using namespace tactus::solver;
using namespace tactus::testkit;

namespace {

// The finger over the handle (finger_kit.hpp, as the grasp tests), adaptive relaxation on.
Scenario relaxing_grasp(const TempDir& dir) {
  Scenario sc = grasp_scenario(dir, 50, 0.03);
  sc.run.threads = 1;
  sc.damping.alpha = 0;
  sc.damping.adaptive = true;
  sc.damping.residual_tolerance = 2e-3;
  sc.damping.residual_after = sc.grasp.ramp_time;
  return sc;
}

}  // namespace

int lockstep(int rank, int ranks) {
  TempDir dir;
  const Scenario sc = relaxing_grasp(dir);
  const Model model = build_model(sc);
  const Decomposition d = decompose(model, ranks);
  RankStressPass shared(model, d, MPI_COMM_WORLD, sc.damping.beta, 1);
  ExplicitSolver one(model, sc.run, sc.damping), on_ranks(model, sc.run, sc.damping, &shared);
  std::size_t contact_steps = 0;
  const Lockstep r = run_in_lockstep(
      one, on_ranks,
      [&] {
        return same(one.displacement(), on_ranks.displacement()) && same(one.half_step_velocity(), on_ranks.half_step_velocity()) &&
               same(one.energies().kinetic, on_ranks.energies().kinetic) &&
               same(one.energies().balance_error(), on_ranks.energies().balance_error()) &&
               same(one.relaxation().alpha(), on_ranks.relaxation().alpha()) &&
               same(one.relaxation().relative_residual(), on_ranks.relaxation().relative_residual()) &&
               same(one.joint_drive()->grip_force(), on_ranks.joint_drive()->grip_force());
      },
      [&] { contact_steps += one.contact_report().normal_force > 0; });
  const bool stepping_right = on_ranks.owned_node_stepping() == (ranks > 1);
  if (rank == 0) {
    std::printf(
        "finger grasping a handle, %zu tets, %d rank(s), %zu atoms: %zu steps, %zu in contact, grip %.4f N, adaptive alpha %.3f /s, "
        "residual %.3e; %d rank(s) differ from the one-process run in any bit of u, v, the energies, the relaxation or the grip",
        model.num_elements, ranks, d.atom_rank.size(), r.steps, contact_steps, one.joint_drive()->grip_force(), one.relaxation().alpha(),
        one.relaxation().relative_residual(), r.ranks_differing);
    if (r.differ) std::printf(" (rank 0 first at step %zu)", r.first_differing);
    std::printf("\nowned-node stepping %s: rank 0 integrates %zu of %zu nodes and sends %zu doubles after each update\n",
                on_ranks.owned_node_stepping() ? "on" : "off", shared.integrated_nodes(), model.num_nodes, shared.ghost_doubles());
    if (!stepping_right) std::printf("FAIL: owned-node stepping should be on over 2 ranks or more, off on one\n");
    if (contact_steps < 20) std::printf("FAIL: the finger should press on the handle for 20 steps or more\n");
  }
  return r.ranks_differing + (contact_steps < 20 ? 1 : 0) + (stepping_right ? 0 : 1);
}

// The handle driven into the finger (bones held) crushes tissue between two rigid bodies: the
// error names the rigid bodies nearest the tet (ExplicitSolver::describe_rigid_neighbours), whose
// nodes only the rank that holds it has once the model has released its connectivity
// (Model::release_tet_geometry). Every rank must throw one process's message, word for word.
std::string crushed_message(const Scenario& sc, StressPassEngine* shared, Model& model) {
  ExplicitSolver s(model, sc.run, sc.damping, shared);
  if (shared) model.release_tet_geometry();
  try {
    while (true) {
      s.advance_velocity();
      if (s.finished()) break;
      s.advance_position();
    }
  } catch (const NumericalError& e) {
    return e.what();
  }
  return "(ran to the end)";
}

int crushed(int rank, int ranks) {
  TempDir dir;
  Scenario sc = grasp_scenario(dir, 50, 0.03);
  sc.run.threads = 1;
  sc.grasp = GraspSpec{};  // the bones held
  sc.bodies[1].rigid_velocity = Vec3{0, 0, 1.0};
  Model alone = build_model(sc), spread = build_model(sc);
  const std::string one = crushed_message(sc, nullptr, alone);
  RankStressPass shared(spread, decompose(spread, ranks), MPI_COMM_WORLD, sc.damping.beta, 1);
  const std::string on_ranks = crushed_message(sc, &shared, spread);
  const bool names_both = on_ranks.find("crushed between two rigid bodies") != std::string::npos;
  const int wrong = on_ranks == one && names_both ? 0 : 1;
  int ranks_wrong = 0;
  MPI_Allreduce(&wrong, &ranks_wrong, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  if (rank == 0)
    std::printf("crushed tissue on %d rank(s), the model's connectivity released: %s\n%d rank(s) throw another message than one process's: %s\n",
                ranks, on_ranks.c_str(), ranks_wrong, one.c_str());
  return ranks_wrong;
}

int main(int argc, char** argv) {
  return rank_test_main(argc, argv, "tactus_test_rank_grasp", [](int rank, int ranks) { return lockstep(rank, ranks) + crushed(rank, ranks); });
}
