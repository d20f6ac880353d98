// The stress pass over MPI ranks (ranks.hpp).
#include <algorithm>
#include <cstring>
#include <limits>
#include <string>

#include "tactus/core/error.hpp"
#include "tactus/solver/ranks.hpp"

namespace tactus::solver {

namespace {

// What a rank contributes to the global result per atom it runs: the atom's index, then its
// accumulator, as doubles (element indices are exact below 2^53).
constexpr int kAtomRecord = 8;

void check(int code, const char* what) {
  if (code != MPI_SUCCESS) throw Error(std::string("MPI: ") + what + " failed (code " + std::to_string(code) + ")");
}

}  // namespace

RankStressPass::RankStressPass(const Model& model, const Decomposition& d, MPI_Comm comm, double beta, int threads)
    : comm_(comm), forces_(model, beta, threads) {
  check(MPI_Comm_rank(comm, &rank_), "MPI_Comm_rank");
  check(MPI_Comm_size(comm, &ranks_), "MPI_Comm_size");
  if (d.atom_tets != kAtomTets)
    throw InputError("decomposition", "atom_tets", std::to_string(kAtomTets) + " (the stress pass's atom)", std::to_string(d.atom_tets));
  if (d.ranks != ranks_) throw InputError("decomposition", "ranks", std::to_string(ranks_) + " (the MPI ranks)", std::to_string(d.ranks));
  forces_.own_atoms(d.tet_atom, d.atom_rank, rank_);
  touched_.assign(model.num_nodes, 0);
  for (std::size_t e = 0; e < model.num_elements; ++e)
    if (d.atom_rank[d.tet_atom[e]] == rank_)
      for (int k = 0; k < 4; ++k) touched_[static_cast<std::size_t>(model.conn[4 * e + static_cast<std::size_t>(k)])] = 1;
  for (const HaloSlots& h : forces_.halo()) {
    send_.emplace_back(InternalForces::kSlotDoubles * h.send.size());
    receive_.emplace_back(InternalForces::kSlotDoubles * h.receive.size());
  }
  requests_.resize(2 * forces_.halo().size());
}

std::size_t RankStressPass::halo_doubles() const {
  std::size_t n = 0;
  for (const auto& s : send_) n += s.size();
  return n;
}

std::size_t RankStressPass::gathered_bytes() const { return forces_.atom_ranks().size() * kAtomRecord * sizeof(double); }

// The master thread, once the boundary atoms are done: their shared slots out, the others' in.
void RankStressPass::start_exchange(void* self) {
  auto& me = *static_cast<RankStressPass*>(self);
  const double* slots = me.forces_.slot_forces();
  const auto& halo = me.forces_.halo();
  for (std::size_t i = 0; i < halo.size(); ++i) {
    double* out = me.send_[i].data();
    for (std::uint32_t s : halo[i].send)
      std::memcpy(out, slots + InternalForces::kSlotDoubles * s, InternalForces::kSlotDoubles * sizeof(double)), out += InternalForces::kSlotDoubles;
    check(MPI_Irecv(me.receive_[i].data(), static_cast<int>(me.receive_[i].size()), MPI_DOUBLE, halo[i].rank, 0, me.comm_, &me.requests_[2 * i]),
          "MPI_Irecv");
    check(MPI_Isend(me.send_[i].data(), static_cast<int>(me.send_[i].size()), MPI_DOUBLE, halo[i].rank, 0, me.comm_, &me.requests_[2 * i + 1]),
          "MPI_Isend");
  }
}

// The master thread, before the nodal sums: the other ranks' slots into place.
void RankStressPass::finish_exchange(void* self) {
  auto& me = *static_cast<RankStressPass*>(self);
  check(MPI_Waitall(static_cast<int>(me.requests_.size()), me.requests_.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
  double* slots = me.forces_.slot_forces();
  const auto& halo = me.forces_.halo();
  for (std::size_t i = 0; i < halo.size(); ++i) {
    const double* in = me.receive_[i].data();
    for (std::uint32_t s : halo[i].receive)
      std::memcpy(slots + InternalForces::kSlotDoubles * s, in, InternalForces::kSlotDoubles * sizeof(double)), in += InternalForces::kSlotDoubles;
  }
}

StressPassResult RankStressPass::compute(const double* u, const double* v, double* f_out) {
  const StressPassResult local = forces_.compute(u, v, f_out, StressSideTask{}, StressExchange{&start_exchange, &finish_exchange, this});
  // Every atom's accumulator on every rank, then the sums in atom order.
  const auto& owner = forces_.atom_ranks();
  const auto& mine = forces_.atom_results();
  std::vector<double> records;
  for (std::size_t p = 0; p < owner.size(); ++p)
    if (owner[p] == rank_) {
      const StressAccumulator& a = mine[p];
      records.insert(records.end(), {static_cast<double>(p), a.energy, a.viscous_power, a.dt2, a.dt, static_cast<double>(a.dt_element), a.min_J,
                                     static_cast<double>(a.min_J_element)});
    }
  std::vector<int> counts(static_cast<std::size_t>(ranks_)), offsets(static_cast<std::size_t>(ranks_), 0);
  const int count = static_cast<int>(records.size());
  check(MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, comm_), "MPI_Allgather");
  for (std::size_t r = 1; r < counts.size(); ++r) offsets[r] = offsets[r - 1] + counts[r - 1];
  std::vector<double> all(static_cast<std::size_t>(offsets.back() + counts.back()));
  check(MPI_Allgatherv(records.data(), count, MPI_DOUBLE, all.data(), counts.data(), offsets.data(), MPI_DOUBLE, comm_), "MPI_Allgatherv");
  std::vector<StressAccumulator> atoms(owner.size());
  for (std::size_t i = 0; i + kAtomRecord <= all.size(); i += kAtomRecord) {
    StressAccumulator& a = atoms[static_cast<std::size_t>(all[i])];
    a.energy = all[i + 1], a.viscous_power = all[i + 2], a.dt2 = all[i + 3], a.dt = all[i + 4];
    a.dt_element = static_cast<std::size_t>(all[i + 5]), a.min_J = all[i + 6], a.min_J_element = static_cast<std::size_t>(all[i + 7]);
  }
  StressPassResult r = forces_.combine_atoms(atoms);
  // The nodal bound: each rank's over the nodes it touches (the others' row sums are 0 there);
  // the smallest step, ties to the smallest node (the serial pass's first chunk).
  struct {
    double step;
    int node;
  } in{local.nodal_critical_step > 0 ? local.nodal_critical_step : std::numeric_limits<double>::infinity(), static_cast<int>(local.limiting_node)},
      out{};
  check(MPI_Allreduce(&in, &out, 1, MPI_DOUBLE_INT, MPI_MINLOC, comm_), "MPI_Allreduce");
  if (out.step < std::numeric_limits<double>::infinity()) {
    r.nodal_critical_step = out.step, r.limiting_node = static_cast<std::size_t>(out.node);
    if (r.nodal_critical_step > r.critical_step) r.critical_step = r.nodal_critical_step, r.limited_by_node = true;
  }
  return r;
}

}  // namespace tactus::solver
