// The explicit integrator over MPI ranks steps as one process does (issue: MPI, "Rank-count
// independence", the self-contact case). A free U-shaped strip (12 x 5 x 20 mm, arms 3 mm thick, a
// 6 mm slot, E = 1 MPa, Rayleigh beta on) whose arms swing into each other at up to 2.5 m/s: its one
// surface is slave and master of one node-to-surface pair. The same model is stepped twice in this
// process, by ExplicitSolver alone (one thread) and with the stress pass spread over the ranks of
// this mpiexec (RankStressPass, METIS atoms), in lockstep. Oracle: the one-process run. On 2 ranks
// or more the run steps owned nodes (each rank integrates its own nodes and the strip's surface,
// the contact nodes); after every step the state is gathered (ExplicitSolver::gather_state) and
// every displacement and half-step velocity component, the energies and the contact force must be
// the same bits on every rank. Run by CTest on 1 to 4 ranks.
#include <mpi.h>

#include <gmsh.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <vector>

#include "gmsh_kit.hpp"
#include "material_kit.hpp"
#include "rank_lockstep.hpp"
#include "tactus/core/gmsh_session.hpp"
#include "tactus/solver/contact.hpp"
#include "tactus/solver/decomposition.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/ranks.hpp"

using namespace tactus;
using namespace tactus::solver;
using namespace tactus::testkit;

namespace {

constexpr double W = 0.012, D = 0.005, Hgt = 0.02, t = 0.003, h = 1.2e-3;

Model u_strip() {
  const TetMesh mesh = testkit::u_strip_mesh(W, D, Hgt, t, h);
  Model model = build_model(mesh, testkit::linear_elastic(1e6, 0.3, 1000));
  for (std::size_t i = 0; i < model.num_nodes; ++i) {
    const double x = model.X[3 * i], z = model.X[3 * i + 2];
    model.initial_velocity[3 * i] = 2.5 * std::clamp((z - t) / (Hgt - t), 0.0, 1.0) * (x < W / 2 ? 1.0 : -1.0);
  }
  ContactPair self;
  self.name = "strip self-contact";
  set_self_contact_surface(self, model, surface_triangles(model, 20), "strip surface");
  model.contact_pairs.push_back(self);
  model.contact_settings.tolerance = 1e-10;
  model.contact_settings.max_iterations = 1000;
  return model;
}

}  // namespace

int lockstep(int rank, int ranks) {
  const Model model = u_strip();
  RunSpec run;
  run.end_time = 3e-3;
  run.threads = 1;
  DampingSpec damping;
  damping.beta = 2e-6;
  const Decomposition d = decompose(model, ranks);
  RankStressPass shared(model, d, MPI_COMM_WORLD, damping.beta, 1);
  ExplicitSolver one(model, run, damping), on_ranks(model, run, damping, &shared);
  std::size_t contact_steps = 0;
  double peak_force = 0;
  const Lockstep r = run_in_lockstep(
      one, on_ranks,
      [&] {
        return same(one.displacement(), on_ranks.displacement()) && same(one.half_step_velocity(), on_ranks.half_step_velocity()) &&
               same(one.energies().kinetic, on_ranks.energies().kinetic) && same(one.energies().internal, on_ranks.energies().internal) &&
               same(one.energies().balance_error(), on_ranks.energies().balance_error()) &&
               same(one.contact_report().normal_force, on_ranks.contact_report().normal_force);
      },
      [&] {
        contact_steps += one.contact_report().normal_force > 0;
        peak_force = std::max(peak_force, one.contact_report().normal_force);
      });
  const bool stepping_right = on_ranks.owned_node_stepping() == (ranks > 1);
  if (rank == 0) {
    std::printf(
        "U strip self-contact, %zu tets, %d rank(s), %zu atoms, faces cut %zu: %zu steps, %zu in contact, peak normal force %.4f N; "
        "%d rank(s) differ from the one-process run in any bit of u, v, the energies or the contact force",
        model.num_elements, ranks, d.atom_rank.size(), d.edge_cut_faces, r.steps, contact_steps, peak_force, r.ranks_differing);
    if (r.differ) std::printf(" (rank 0 first at step %zu)", r.first_differing);
    std::printf("\nowned-node stepping %s: rank 0 integrates %zu of %zu nodes and sends %zu doubles after each update\n",
                on_ranks.owned_node_stepping() ? "on" : "off", shared.integrated_nodes(), model.num_nodes, shared.ghost_doubles());
    if (!stepping_right) std::printf("FAIL: owned-node stepping should be on over 2 ranks or more, off on one\n");
    if (contact_steps < 50) std::printf("FAIL: the arms should press on each other for 50 steps or more\n");
  }
  return r.ranks_differing + (contact_steps < 50 ? 1 : 0) + (stepping_right ? 0 : 1);
}

int main(int argc, char** argv) { return rank_test_main(argc, argv, "tactus_test_rank_solve", lockstep); }
