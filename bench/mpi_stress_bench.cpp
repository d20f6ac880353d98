// The stress pass over MPI ranks, timed (issue: MPI, "Performance"; run by bench/mpi_scaling.sh).
// Every rank builds the same model (a Morton-ordered box of 6 n^3 tets, or one .msh file's tets,
// all neo-Hookean, standard tets or with --formulation anp ANP tets), splits it with METIS
// into the mpiexec's ranks (atoms of kAtomTets tets) and times --rounds passes of RankStressPass
// (the halo exchange overlapped with the interior atoms, the per-atom records gathered, the nodal
// bound reduced) on a smooth deformation: per round the slowest rank's time, between barriers.
// On one rank it also times the plain one-process pass (InternalForces) alternately, to show the
// rank machinery's own cost. Prints the median and range, tets and halo per rank (doubles sent and
// messages per pass), and the bytes of the per-atom records every rank receives per pass.
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "tactus/core/error.hpp"
#include "tactus/core/mesh.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/decomposition.hpp"
#include "tactus/solver/internal_force.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/ranks.hpp"

using namespace tactus;
using namespace tactus::solver;

namespace {

// formulation: "standard", or "anp" (average nodal pressure tets, 2 smoothing passes: the ranks'
// J pass over their ghost regions).
Material neo_hookean(const std::string& formulation) {
  MaterialValues v;
  v.numbers = {{"mu", 3000.0}, {"bulk", 50000.0}, {"density", 1000.0}};
  v.strings = {{"formulation", formulation}};
  return Material::make("neo_hookean", v, "bench");
}

double median(std::vector<double> x) {
  std::sort(x.begin(), x.end());
  return x[x.size() / 2];
}

// The slowest rank's seconds for one call of pass(), the ranks lined up by a barrier first.
template <class Pass>
double timed(Pass&& pass) {
  MPI_Barrier(MPI_COMM_WORLD);
  const auto t0 = std::chrono::steady_clock::now();
  pass();
  double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), slowest = 0;
  MPI_Allreduce(&s, &slowest, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return slowest;
}

template <class T>
std::vector<T> gathered(T mine, MPI_Datatype type, int ranks) {
  std::vector<T> all(static_cast<std::size_t>(ranks));
  MPI_Allgather(&mine, 1, type, all.data(), 1, type, MPI_COMM_WORLD);
  return all;
}

template <class T>
std::string listed(const std::vector<T>& x) {
  std::string s;
  for (const T& v : x) {
    if (!s.empty()) s += ' ';
    s += std::to_string(v);
  }
  return s;
}

int run(int argc, char** argv) {
  int cells = 55, rounds = 7, threads = 1;
  std::string mesh_file, formulation = "standard";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i], value = argv[i + 1];
    if (key == "--cells")
      cells = std::stoi(value);
    else if (key == "--rounds")
      rounds = std::stoi(value);
    else if (key == "--threads")
      threads = std::stoi(value);
    else if (key == "--mesh")
      mesh_file = value;
    else if (key == "--formulation")
      formulation = value;
    else
      throw Error("tactus-bench-mpi: unknown option " + key + " (--cells N | --mesh FILE.msh, --rounds K, --threads T, --formulation standard|anp)");
  }
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  const TetMesh mesh = mesh_file.empty() ? samples::make_box_mesh(cells, cells, cells, 0.1, 0.1, 0.1) : read_msh(mesh_file);
  const Model model = build_model(mesh, neo_hookean(formulation), "soft");
  std::vector<double> u(3 * model.num_nodes), v(3 * model.num_nodes), f(3 * model.num_nodes);
  for (std::size_t n = 0; n < model.num_nodes; ++n) {  // a smooth stretch and twist, and a velocity
    const double x = model.X[3 * n], y = model.X[3 * n + 1], z = model.X[3 * n + 2];
    u[3 * n] = 0.05 * x + 0.002 * std::sin(300 * y), u[3 * n + 1] = -0.02 * y + 0.001 * std::cos(250 * z), u[3 * n + 2] = 0.3 * z * x;
    v[3 * n] = std::sin(100 * z), v[3 * n + 1] = 0.5 * std::cos(90 * x), v[3 * n + 2] = 0.2 * y;
  }
  const Decomposition d = decompose(model, ranks);
  RankStressPass pass(model, d, MPI_COMM_WORLD, 0.0, threads);
  InternalForces one(model, 0.0, threads);
  std::vector<double> rank_times, one_times;
  pass.compute(u.data(), v.data(), f.data());  // first touch
  for (int r = 0; r < rounds; ++r) {
    rank_times.push_back(timed([&] { pass.compute(u.data(), v.data(), f.data()); }));
    if (ranks == 1) one_times.push_back(timed([&] { one.compute(u.data(), v.data(), f.data()); }));
  }
  const auto tets = static_cast<long>(pass.tets()), messages = static_cast<long>(pass.halo_ranks());
  const auto all_tets = gathered(tets, MPI_LONG, ranks);
  const auto all_halo = gathered(static_cast<long>(pass.halo_doubles()), MPI_LONG, ranks);
  const auto all_messages = gathered(messages, MPI_LONG, ranks);
  if (rank == 0) {
    std::printf("ranks %d x threads %d: %zu tets, %zu atoms, faces cut %zu; stress pass median %.3f ms (%.3f .. %.3f) over %d rounds\n", ranks,
                threads, model.num_elements, d.atom_rank.size(), d.edge_cut_faces, 1e3 * median(rank_times),
                1e3 * *std::min_element(rank_times.begin(), rank_times.end()), 1e3 * *std::max_element(rank_times.begin(), rank_times.end()), rounds);
    if (!one_times.empty()) std::printf("  one-process pass (InternalForces) median %.3f ms, alternated with it\n", 1e3 * median(one_times));
    std::printf("  tets per rank: %s\n  halo doubles sent per rank per pass: %s\n  halo messages sent per rank per pass: %s\n",
                listed(all_tets).c_str(), listed(all_halo).c_str(), listed(all_messages).c_str());
    std::printf("  per-atom records every rank receives per pass (MPI_Allgatherv): %zu bytes\n", pass.gathered_bytes());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int status = 0;
  try {
    status = run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    MPI_Abort(MPI_COMM_WORLD, 2);
  }
  MPI_Finalize();
  return status;
}
