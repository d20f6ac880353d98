// tactus-solve under mpirun (ranks.hpp): the session, the handshake and the decomposition.
#include <mpi.h>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <utility>

#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"
#include "tactus/solver/ranks.hpp"

namespace tactus::solver {

namespace {

// 64-bit FNV-1a, one value at a time.
struct Fnv1a {
  std::uint64_t h = 1469598103934665603ull;
  void add(std::uint64_t x) { h = (h ^ x) * 1099511628211ull; }
};

// Of a file's bytes (0 when it cannot be read).
std::uint64_t file_hash(const char* path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return 0;
  Fnv1a f;
  char buffer[1 << 16];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
    for (std::streamsize i = 0; i < in.gcount(); ++i) f.add(static_cast<unsigned char>(buffer[i]));
    if (!in) break;
  }
  return f.h;
}

std::uint64_t parts_checksum(const Decomposition& d) {
  Fnv1a f;
  for (std::int32_t r : d.atom_rank) f.add(static_cast<std::uint64_t>(r));
  return f.h ^ d.atom_rank.size();
}

// The smallest and the largest of a value over every rank (collective): equal when every rank has it.
std::pair<unsigned long long, unsigned long long> range_over_ranks(unsigned long long mine) {
  unsigned long long low = 0, high = 0;
  MPI_Allreduce(&mine, &low, 1, MPI_UNSIGNED_LONG_LONG, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(&mine, &high, 1, MPI_UNSIGNED_LONG_LONG, MPI_MAX, MPI_COMM_WORLD);
  return {low, high};
}

}  // namespace

bool started_by_mpirun() { return std::getenv("OMPI_COMM_WORLD_SIZE") || std::getenv("PMIX_RANK"); }

RankSession::RankSession(int* argc, char*** argv) {
  int provided = 0;
  if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) throw Error("MPI: MPI_Init_thread failed");
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks_);
  MPI_Comm_dup(MPI_COMM_WORLD, &stop_comm_);
  if (provided < MPI_THREAD_FUNNELED) {
    MPI_Finalize();
    throw Error("MPI: this MPI library gives no MPI_THREAD_FUNNELED (the stress pass's threads need it)");
  }
}

RankSession::~RankSession() {
  MPI_Comm_free(&stop_comm_);
  MPI_Finalize();
}

bool RankSession::all_stopped_within(double seconds) const {
  MPI_Request request = MPI_REQUEST_NULL;
  MPI_Ibarrier(stop_comm_, &request);
  const double until = MPI_Wtime() + seconds;
  int done = 0;
  while (MPI_Test(&request, &done, MPI_STATUS_IGNORE) == MPI_SUCCESS && !done && MPI_Wtime() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  return done != 0;
}

void RankSession::abort(int code) const {
  MPI_Abort(MPI_COMM_WORLD, code);
  std::_Exit(code);
}

void RankSession::check_same_build() const {
  const auto mine = static_cast<unsigned long long>(file_hash("/proc/self/exe"));
  std::vector<unsigned long long> all(static_cast<std::size_t>(ranks_));
  MPI_Allgather(&mine, 1, MPI_UNSIGNED_LONG_LONG, all.data(), 1, MPI_UNSIGNED_LONG_LONG, MPI_COMM_WORLD);
  for (std::size_t r = 1; r < all.size(); ++r)
    if (all[r] != all[0] || all[0] == 0) {
      std::ostringstream want, got;
      want << "the same tactus-solve build on every rank (rank 0's executable hashes to " << std::hex << all[0] << ")";
      got << "rank " << std::dec << r << "'s hashes to " << std::hex << all[r];
      throw InputError("mpirun", "tactus-solve executable", want.str(), got.str());
    }
}

RankRun RankSession::run(const std::filesystem::path& partition) const {
  RankRun run;
  run.rank = rank_, run.ranks = ranks_;
  const int ranks = ranks_, rank = rank_;
  run.stress_pass = [partition, ranks, rank](const Model& model, double beta, int threads) -> std::unique_ptr<StressPassEngine> {
    const std::size_t limit = model.num_elements / 8;
    if (static_cast<std::size_t>(ranks) > limit)
      throw InputError("mpirun", "-np",
                       "at most " + std::to_string(limit) + " ranks for this model (its " + std::to_string(model.num_elements) + " tets / 8)",
                       std::to_string(ranks));
    const Decomposition d = partition.empty() ? decompose(model, ranks, kAtomTets, "mpirun -np") : read_partition(model, partition);
    if (d.ranks != ranks) throw InputError(partition.string(), "ranks", std::to_string(ranks) + " (mpirun -np)", std::to_string(d.ranks));
    const auto [low, high] = range_over_ranks(parts_checksum(d));
    if (low != high) throw Error("MPI: the ranks decomposed the model differently (METIS gave different parts on different ranks)");
    if (rank == 0)
      log::info() << "decomposition" << (partition.empty() ? " (METIS)" : " (" + partition.string() + ")") << ":\n" << format_decomposition(d);
    return std::make_unique<RankStressPass>(model, d, MPI_COMM_WORLD, beta, threads);
  };
  run.rank0_decides = [](bool due) {
    int flag = due ? 1 : 0;
    if (MPI_Bcast(&flag, 1, MPI_INT, 0, MPI_COMM_WORLD) != MPI_SUCCESS) throw Error("MPI: MPI_Bcast failed");
    return flag != 0;
  };
  run.rank0_text = [rank](const std::string& text) {
    unsigned long long size = text.size();
    std::string out = text;
    if (MPI_Bcast(&size, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD) != MPI_SUCCESS) throw Error("MPI: MPI_Bcast failed");
    if (rank != 0) out.assign(size, '\0');
    if (MPI_Bcast(out.data(), static_cast<int>(size), MPI_CHAR, 0, MPI_COMM_WORLD) != MPI_SUCCESS) throw Error("MPI: MPI_Bcast failed");
    return out;
  };
  run.all_meet = [] {
    if (MPI_Barrier(MPI_COMM_WORLD) != MPI_SUCCESS) throw Error("MPI: MPI_Barrier failed");
  };
  run.check_same_restart = [](std::size_t step) {
    const auto [low, high] = range_over_ranks(step);
    if (low != high)
      throw InputError("mpirun", "checkpoint", "every rank continuing from the same checkpoint (another process may be writing that folder)",
                       "steps " + std::to_string(low == 0 ? 0 : low - 1) + " and " + std::to_string(high - 1));
  };
  return run;
}

}  // namespace tactus::solver
