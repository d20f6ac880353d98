#pragma once
// What the lockstep rank tests share (test_rank_solve.cpp, test_rank_grasp.cpp): bit-for-bit
// comparison, and a main that runs a test body on every rank of this mpiexec and ends the job
// with a message should a rank throw (its partners would wait for it in a collective).
#include <mpi.h>

#include <cstdio>
#include <cstring>
#include <exception>
#include <vector>

#include "tactus/solver/explicit.hpp"

namespace tactus::testkit {

inline bool same(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}
inline bool same(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

// Two solvers of one model, one process's and one over the ranks, stepped together to the end (or
// until the run relaxes); after every velocity update the ranks' state is gathered, `same_step`
// compares the two and `each` sees the one-process solver. Returns the steps, whether and where
// this rank first differed, and how many ranks differed (collective).
struct Lockstep {
  std::size_t steps = 0, first_differing = 0;
  int differ = 0, ranks_differing = 0;
};
template <class Same, class Each>
Lockstep run_in_lockstep(solver::ExplicitSolver& one, solver::ExplicitSolver& on_ranks, Same&& same_step, Each&& each) {
  Lockstep r;
  while (true) {
    one.advance_velocity(), on_ranks.advance_velocity();
    on_ranks.gather_state();
    if (!same_step() && !r.differ) r.differ = 1, r.first_differing = one.step_index();
    each();
    if (one.finished() || one.relaxed()) break;
    one.advance_position(), on_ranks.advance_position();
    ++r.steps;
  }
  MPI_Allreduce(&r.differ, &r.ranks_differing, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  return r;
}

// MPI_Init_thread (FUNNELED, as tactus-solve), body(rank, ranks) returning its failures, then
// MPI_Finalize; the exit status is 0 when every check passed.
inline int rank_test_main(int argc, char** argv, const char* name, int (*body)(int rank, int ranks)) {
  int provided = 0, rank = 0, ranks = 1;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  int failures = 0;
  try {
    failures = body(rank, ranks);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", name, e.what());
    MPI_Abort(MPI_COMM_WORLD, 2);
  }
  MPI_Finalize();
  return failures == 0 ? 0 : 1;
}

}  // namespace tactus::testkit
