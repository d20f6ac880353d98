// The stress pass over MPI ranks gives one process's bits (issue: MPI, "How the bits stay the
// same"). A box of 5,184 tets in two material blocks (neo-Hookean, as standard and then as ANP
// tets, and linear elastic; Rayleigh beta on, the nodal step bound on), deformed by a smooth field with a velocity, its stress pass
// run by one process (InternalForces) and by RankStressPass on the ranks of this mpiexec, split
// twice: by METIS and with the atoms dealt round-robin (a cut through nearly every atom boundary).
// Oracle: the one-process pass. Every force component at every node a rank touches, the strain
// energy, viscous power, both step bounds with their limiting tet and node, and the smallest J
// must be the same bits (memcmp), on every rank. Run by CTest on 1 to 4 ranks.
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "material_kit.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/decomposition.hpp"
#include "tactus/solver/internal_force.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/ranks.hpp"

using namespace tactus;
using namespace tactus::solver;

namespace {

// formulation: of the soft block ("anp": its J pass, by exchanges of the halo slots' volumes and
// of the ghost nodes' values after each smoothing pass, and the nodal bound's ANP form, whose tiles
// at shared nodes travel with the halo and whose largest rows per eta are reduced before the step);
// smoothing: its pressure smoothing passes (ANP; 0: plain ANP, the chunks' energies alone need
// ghost nodes).
Model two_block_model(const char* formulation, int smoothing) {
  const TetMesh mesh = samples::make_box_mesh(12, 12, 6, 0.024, 0.024, 0.012);
  Model model = build_model(
      mesh, testkit::make_law("neo_hookean", {{"mu", 3000}, {"bulk", 50000}, {"density", 1000}, {"pressure_smoothing", smoothing}}, {}, formulation),
      "soft");
  MaterialBlock stiff{"stiff", testkit::linear_elastic(2e5, 0.3, 1100), 3000, model.num_elements, {}, false};
  model.blocks[0].end = 3000;  // the Morton order interleaves the two blocks in space
  model.blocks.push_back(std::move(stiff));
  return model;
}

bool same(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

// Mismatches of this rank against the one-process pass, printed by rank 0 with the figures.
int compare(const char* split, const Model& model, const Decomposition& d, const std::vector<double>& u, const std::vector<double>& v,
            const std::vector<double>& f_one, const StressPassResult& one) {
  RankStressPass ranks(model, d, MPI_COMM_WORLD, 1e-4, 0);
  std::vector<double> f(3 * model.num_nodes, 0.0);
  const StressPassResult r = ranks.compute(u.data(), v.data(), f.data());
  int differ = 0, compared = 0;
  for (std::size_t n = 0; n < model.num_nodes; ++n)
    if (ranks.touched()[n])
      for (int i = 0; i < 3; ++i) ++compared, differ += !same(f[3 * n + i], f_one[3 * n + i]);
  const bool result_same = same(r.strain_energy, one.strain_energy) && same(r.viscous_power, one.viscous_power) &&
                           same(r.critical_step, one.critical_step) && same(r.element_critical_step, one.element_critical_step) &&
                           same(r.nodal_critical_step, one.nodal_critical_step) && r.limiting_element == one.limiting_element &&
                           r.limiting_node == one.limiting_node && r.limited_by_node == one.limited_by_node &&
                           same(r.min_jacobian, one.min_jacobian) && r.min_jacobian_element == one.min_jacobian_element;
  int all_differ = 0, all_compared = 0, results_differ = result_same ? 0 : 1, all_results_differ = 0;
  unsigned long halo = ranks.halo_doubles(), all_halo = 0;
  MPI_Allreduce(&differ, &all_differ, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  MPI_Allreduce(&compared, &all_compared, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  MPI_Allreduce(&results_differ, &all_results_differ, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  MPI_Allreduce(&halo, &all_halo, 1, MPI_UNSIGNED_LONG, MPI_SUM, MPI_COMM_WORLD);
  if (ranks.rank() == 0) {
    std::printf(
        "%s, %d rank(s), %zu atoms, faces cut %zu: %d of %d force components (nodes as each rank touches them) differ in any bit; "
        "halo %lu doubles per pass\n",
        split, d.ranks, d.atom_rank.size(), d.edge_cut_faces, all_differ, all_compared, all_halo);
    std::printf("  strain energy %.17g J (one process %.17g), viscous power %.17g W (%.17g)\n", r.strain_energy, one.strain_energy, r.viscous_power,
                one.viscous_power);
    std::printf(
        "  step %.17g s (%.17g), element %.17g at tet %zu (%zu), nodal %.17g at node %zu (%zu), smallest J %.17g at tet %zu (%zu); "
        "%d rank(s) differ\n",
        r.critical_step, one.critical_step, r.element_critical_step, r.limiting_element, one.limiting_element, r.nodal_critical_step, r.limiting_node,
        one.limiting_node, r.min_jacobian, r.min_jacobian_element, one.min_jacobian_element, all_results_differ);
  }
  return all_differ + all_results_differ;
}

}  // namespace

int main(int argc, char** argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int ranks = 1, rank = 0, failures = 0;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  try {
    for (const auto& [formulation, smoothing] : {std::pair<const char*, int>{"standard", 0}, {"anp", 2}, {"anp", 0}}) {
      const Model model = two_block_model(formulation, smoothing);
      if (rank == 0) std::printf("soft block: %s tets%s\n", formulation, smoothing ? ", 2 smoothing passes" : "");
      std::vector<double> u(3 * model.num_nodes), v(3 * model.num_nodes);
      for (std::size_t n = 0; n < model.num_nodes; ++n) {  // a smooth stretch and twist, and a velocity
        const double x = model.X[3 * n], y = model.X[3 * n + 1], z = model.X[3 * n + 2];
        u[3 * n] = 0.05 * x + 0.002 * std::sin(300 * y), u[3 * n + 1] = -0.02 * y + 0.001 * std::cos(250 * z), u[3 * n + 2] = 0.3 * z * x;
        v[3 * n] = std::sin(100 * z), v[3 * n + 1] = 0.5 * std::cos(90 * x), v[3 * n + 2] = 0.2 * y;
      }
      InternalForces one(model, 1e-4, 0);
      std::vector<double> f_one(3 * model.num_nodes);
      const StressPassResult r_one = one.compute(u.data(), v.data(), f_one.data());
      Decomposition metis = decompose(model, ranks);
      failures += compare("METIS", model, metis, u, v, f_one, r_one);
      Decomposition dealt = metis;
      for (std::size_t a = 0; a < dealt.atom_rank.size(); ++a) dealt.atom_rank[a] = static_cast<std::int32_t>(a % static_cast<std::size_t>(ranks));
      dealt.edge_cut_faces = 0;  // not measured for this split (printed as 0)
      failures += compare("round-robin", model, dealt, u, v, f_one, r_one);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tactus_test_ranks: %s\n", e.what());
    MPI_Abort(MPI_COMM_WORLD, 2);
  }
  MPI_Finalize();
  return failures == 0 ? 0 : 1;
}
