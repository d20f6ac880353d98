// The stress pass over MPI ranks (ranks.hpp).
#include <algorithm>
#include <array>
#include <cstring>
#include <fstream>
#include <limits>
#include <numeric>
#include <string>

#include "tactus/core/error.hpp"
#include "tactus/solver/ranks.hpp"

namespace tactus::solver {

namespace {

// What a rank contributes to the sums: its atoms' and chunks' energy and its atoms' viscous power,
// each as an exact accumulator's words (ExactSum: added over the ranks in any order, the same bits).
constexpr std::size_t kSumRecord = 2 * ExactSum::kWords;

// This process's resident memory (Linux: `VmHWM:` its peak, `VmRSS:` now), bytes; 0 where it
// cannot be read.
double resident_bytes(const char* which) {
  std::ifstream status("/proc/self/status");
  std::string key;
  double kilobytes = 0;
  while (status >> key)
    if (key == which && status >> kilobytes) return 1024 * kilobytes;
  return 0;
}

void check(int code, const char* what) {
  if (code != MPI_SUCCESS) throw Error(std::string("MPI: ") + what + " failed (code " + std::to_string(code) + ")");
}

}  // namespace

RankStressPass::RankStressPass(const Model& model, const Decomposition& d, MPI_Comm comm, double beta, int threads)
    : model_(model), beta_(beta), comm_(comm), forces_(model, beta, threads) {
  check(MPI_Comm_rank(comm, &rank_), "MPI_Comm_rank");
  check(MPI_Comm_size(comm, &ranks_), "MPI_Comm_size");
  if (d.atom_tets != kAtomTets)
    throw InputError("decomposition", "atom_tets", std::to_string(kAtomTets) + " (the stress pass's atom)", std::to_string(d.atom_tets));
  if (d.ranks != ranks_) throw InputError("decomposition", "ranks", std::to_string(ranks_) + " (the MPI ranks)", std::to_string(d.ranks));
  forces_.own_atoms(d.tet_atom, d.atom_rank, rank_);
  rank_tets_.assign(static_cast<std::size_t>(ranks_), 0);
  for (std::size_t e = 0; e < model.num_elements; ++e) {
    const std::int32_t r = d.atom_rank[d.tet_atom[e]];
    if (tet_runs_.empty() || tet_runs_.back().rank != r)
      tet_runs_.push_back({e, e + 1, r});
    else
      tet_runs_.back().end = e + 1;
    ++rank_tets_[static_cast<std::size_t>(r)];
  }
  std::vector<TetRange> own;
  for (const TetRun& run : tet_runs_)
    if (run.rank == rank_) own.push_back({run.begin, run.end});
  forces_.hold_own_geometry(own);
  for (const HaloSlots& h : forces_.halo()) {
    send_.emplace_back(InternalForces::kSlotDoubles * h.send.size() + h.send_tiles.size());
    receive_.emplace_back(InternalForces::kSlotDoubles * h.receive.size() + h.receive_tiles.size());
  }
  requests_.resize(2 * forces_.halo().size());
  anp_ghost_buffers_.sized_for(forces_.anp_ghosts(), 1);
  // Tets and nodes travel as MPI ints in the MINLOC.
  if (model.num_elements > static_cast<std::size_t>(std::numeric_limits<int>::max()) ||
      model.num_nodes > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw InputError("model", "size", "fewer than 2^31 tets and nodes on ranks", std::to_string(model.num_elements) + " tets");
  // What each rank sends in the pass's gather is fixed: its sums (the exact accumulators of its
  // atoms' and, with ANP blocks, of the node chunks it reports: InternalForces::chunk_ranks, its J
  // pass runs over its own and ghost nodes only), its minima, and for the integrator its owned
  // nodes' forces (who owns which node is fixed too).
  forces_order_.build(forces_.node_ranks(), ranks_, 3);
  layout_gathers();
}

void RankStressPass::layout_gathers() {
  const auto ranks = static_cast<std::size_t>(ranks_);
  constexpr int head = static_cast<int>(kSumRecord) + 2 * kMinima;  // before the forces
  for (Gather* g : {&sums_only_, &with_forces_}) {
    g->counts.resize(ranks), g->offsets.resize(ranks), g->forces_at.resize(ranks);
    for (std::size_t r = 0; r < ranks; ++r) g->counts[r] = head + (g == &with_forces_ ? forces_order_.counts[r] : 0);
    std::exclusive_scan(g->counts.begin(), g->counts.end(), g->offsets.begin(), 0);
    for (std::size_t r = 0; r < ranks; ++r) g->forces_at[r] = static_cast<std::size_t>(g->offsets[r] + head);
  }
  // Fresh arrays, not resized ones: laid out again for owned-node stepping the gather shrinks from
  // every owned node's forces to the everywhere nodes' (a resize would keep the first capacity).
  gathered_ = std::vector<double>(static_cast<std::size_t>(with_forces_.offsets.back() + with_forces_.counts.back()), 0.0);
  records_ = std::vector<double>();
  records_.reserve(static_cast<std::size_t>(with_forces_.counts[static_cast<std::size_t>(rank_)]));
}

void RankStressPass::RankOrder::build(const std::vector<std::int32_t>& item_rank, int ranks, std::size_t per_item) {
  width = per_item;
  counts.assign(static_cast<std::size_t>(ranks), 0), offsets.assign(static_cast<std::size_t>(ranks), 0);
  for (std::int32_t r : item_rank)
    if (r >= 0) counts[static_cast<std::size_t>(r)] += static_cast<int>(width);
  std::exclusive_scan(counts.begin(), counts.end(), offsets.begin(), 0);
  items = std::vector<std::uint32_t>(static_cast<std::size_t>(offsets.back() + counts.back()) / width);
  std::vector<std::size_t> next(static_cast<std::size_t>(ranks));
  for (std::size_t r = 0; r < next.size(); ++r) next[r] = static_cast<std::size_t>(offsets[r]) / width;
  for (std::size_t i = 0; i < item_rank.size(); ++i)
    if (item_rank[i] >= 0) items[next[static_cast<std::size_t>(item_rank[i])]++] = static_cast<std::uint32_t>(i);
  mine = std::vector<double>(), all = std::vector<double>();  // gather's, sized there: pack and unpack need neither
}

void RankStressPass::RankOrder::gather(const double* from, double* to, int rank, MPI_Comm comm) {
  const std::size_t first = static_cast<std::size_t>(offsets[static_cast<std::size_t>(rank)]) / width;
  mine.resize(width * own_items(rank)), all.resize(width * items.size());  // once: the sizes are fixed
  for (std::size_t k = 0; k < own_items(rank); ++k) std::memcpy(&mine[width * k], from + width * items[first + k], width * sizeof(double));
  check(MPI_Allgatherv(mine.data(), static_cast<int>(mine.size()), MPI_DOUBLE, all.data(), counts.data(), offsets.data(), MPI_DOUBLE, comm),
        "MPI_Allgatherv");
  for (std::size_t k = 0; k < items.size(); ++k) std::memcpy(to + width * items[k], &all[width * k], width * sizeof(double));
}

void RankStressPass::RankOrder::pack(const double* from, int rank, std::vector<double>& out) const {
  const std::size_t first = static_cast<std::size_t>(offsets[static_cast<std::size_t>(rank)]) / width, at = out.size();
  out.resize(at + width * own_items(rank));  // within the reserved size: no allocation
  double* to = out.data() + at;
  for (std::size_t k = 0; k < own_items(rank); ++k) std::memcpy(to + width * k, from + width * items[first + k], width * sizeof(double));
}

void RankStressPass::RankOrder::unpack(const double* all_ranks, const std::vector<std::size_t>& rank_at, int rank, double* to) const {
  for (std::size_t r = 0; r < rank_at.size(); ++r) {
    if (static_cast<int>(r) == rank) continue;  // its own items are in place
    const std::size_t first = static_cast<std::size_t>(offsets[r]) / width;
    const double* in = all_ranks + rank_at[r];
    for (std::size_t k = 0; k < own_items(static_cast<int>(r)); ++k)
      std::memcpy(to + width * items[first + k], in + width * k, width * sizeof(double));
  }
}

std::size_t RankStressPass::RankOrder::memory_bytes() const {
  return items.capacity() * sizeof(std::uint32_t) + (counts.capacity() + offsets.capacity()) * sizeof(int) +
         (mine.capacity() + all.capacity()) * sizeof(double);
}

void RankStressPass::enable_mass_scaling() { forces_.enable_mass_scaling(); }

std::vector<FloorTet> RankStressPass::raise_to_floor(double floor2) {
  std::vector<FloorTet> mine;
  forces_.raise_to_floor(floor2, mine);
  constexpr int kWidth = 8;  // tet, rho V, factor before and after, 4 nodes (exact as doubles)
  std::vector<double> send;
  send.reserve(kWidth * mine.size());
  for (const FloorTet& t : mine) {
    send.insert(send.end(), {static_cast<double>(t.tet), t.rho_v, t.factor_before, t.factor_after});
    for (const std::int32_t n : t.nodes) send.push_back(static_cast<double>(n));
  }
  const int count = static_cast<int>(send.size());
  std::vector<int> counts(static_cast<std::size_t>(ranks_)), offsets(static_cast<std::size_t>(ranks_) + 1, 0);
  check(MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, comm_), "MPI_Allgather");
  for (std::size_t r = 0; r < counts.size(); ++r) offsets[r + 1] = offsets[r] + counts[r];
  std::vector<double> all(static_cast<std::size_t>(offsets.back()));
  check(MPI_Allgatherv(send.data(), count, MPI_DOUBLE, all.data(), counts.data(), offsets.data(), MPI_DOUBLE, comm_), "MPI_Allgatherv");
  std::vector<FloorTet> below(all.size() / kWidth);
  for (std::size_t k = 0; k < below.size(); ++k) {
    const double* t = &all[kWidth * k];
    below[k] = {static_cast<std::size_t>(t[0]),
                t[1],
                t[2],
                t[3],
                {static_cast<std::int32_t>(t[4]), static_cast<std::int32_t>(t[5]), static_cast<std::int32_t>(t[6]), static_cast<std::int32_t>(t[7])}};
  }
  // Each rank's ascending; ranks own interleaved runs of tets, so the tet order is a sort.
  std::sort(below.begin(), below.end(), [](const FloorTet& a, const FloorTet& b) { return a.tet < b.tet; });
  return below;
}

std::vector<double> RankStressPass::mass_factors_everywhere() {
  // This rank's held factors are its runs' tets in ascending order; rank 0 places each rank's by
  // its runs.
  const std::vector<double>& mine = forces_.mass_factors();
  std::vector<int> counts(rank_tets_.begin(), rank_tets_.end()), offsets(static_cast<std::size_t>(ranks_) + 1, 0);
  for (std::size_t r = 0; r < counts.size(); ++r) offsets[r + 1] = offsets[r] + counts[r];
  std::vector<double> all(rank_ == 0 ? model_.num_elements : 0), whole;
  check(MPI_Gatherv(mine.data(), static_cast<int>(mine.size()), MPI_DOUBLE, all.data(), counts.data(), offsets.data(), MPI_DOUBLE, 0, comm_),
        "MPI_Gatherv");
  if (rank_ != 0) return whole;
  whole.resize(model_.num_elements);
  std::vector<std::size_t> at(offsets.begin(), offsets.end() - 1);
  for (const TetRun& run : tet_runs_)
    for (std::size_t e = run.begin; e < run.end; ++e) whole[e] = all[at[static_cast<std::size_t>(run.rank)]++];
  return whole;
}

std::pair<double, std::size_t> RankStressPass::smallest_scaled_step(double beta) {
  const std::pair<double, std::size_t> mine = forces_.smallest_scaled_step(beta);
  // MPI_MINLOC: the smallest step, and at a tie the first tet, as one process's scan in tet order
  // (a rank that runs no tet with a stress pass offers infinity; tets fit an int, constructor).
  constexpr double kNone = std::numeric_limits<double>::infinity();
  struct {
    double step;
    int tet;
  } offer{mine.first, mine.first < kNone ? static_cast<int>(mine.second) : std::numeric_limits<int>::max()}, best{};
  check(MPI_Allreduce(&offer, &best, 1, MPI_DOUBLE_INT, MPI_MINLOC, comm_), "MPI_Allreduce");
  return {best.step, best.step < kNone ? static_cast<std::size_t>(best.tet) : std::numeric_limits<std::size_t>::max()};
}

std::size_t RankStressPass::memory_bytes() const {
  std::size_t b =
      forces_.memory_bytes() + forces_order_.memory_bytes() + nodes_order_.memory_bytes() + integrated_dofs_.capacity() * sizeof(std::uint32_t);
  for (const RankOrder& o : chunk_orders_) b += o.memory_bytes();
  for (const Gather* g : {&sums_only_, &with_forces_})
    b += (g->counts.capacity() + g->offsets.capacity()) * sizeof(int) + g->forces_at.capacity() * sizeof(std::size_t);
  for (const auto& s : send_) b += s.capacity() * sizeof(double);
  for (const auto& s : receive_) b += s.capacity() * sizeof(double);
  b += anp_ghost_buffers_.memory_bytes() + state_buffers_.memory_bytes();
  b += (records_.capacity() + gathered_.capacity()) * sizeof(double) + tet_runs_.capacity() * sizeof(TetRun);
  return b;
}

std::vector<std::uint32_t> RankStressPass::checkpoint_nodes() const {
  std::vector<std::uint32_t> nodes;
  const std::vector<std::int32_t>& owner = forces_.node_ranks();
  for (std::size_t n = 0; n < owner.size(); ++n)
    if (owner[n] == rank_ || (owner[n] < 0 && rank_ == 0)) nodes.push_back(static_cast<std::uint32_t>(n));
  return nodes;
}

std::size_t RankStressPass::halo_doubles() const {
  std::size_t n = 0;
  for (const auto& s : send_) n += s.size();
  return n;
}

std::size_t RankStressPass::gathered_bytes() const { return gathered_.size() * sizeof(double); }

// The master thread, once the boundary atoms are done: their shared slots out, the others' in.
void RankStressPass::start_exchange(void* self) {
  auto& me = *static_cast<RankStressPass*>(self);
  const double* slots = me.forces_.slot_forces();
  const auto& halo = me.forces_.halo();
  for (std::size_t i = 0; i < halo.size(); ++i) {
    double* out = me.send_[i].data();
    for (std::uint32_t s : halo[i].send)
      std::memcpy(out, slots + InternalForces::kSlotDoubles * s, InternalForces::kSlotDoubles * sizeof(double)), out += InternalForces::kSlotDoubles;
    for (std::uint32_t t : halo[i].send_tiles) *out++ = me.forces_.anp_tile_values()[t];
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
    for (std::uint32_t t : halo[i].receive_tiles) me.forces_.anp_tile_values()[t] = *in++;
  }
}

// The master thread, in the ANP J pass once this rank's ANP atoms have their nodal volumes: the
// shared slots' volumes out, the others' in (the halo's slots, 1 double each; blocking).
void RankStressPass::exchange_volumes(void* self) {
  auto& me = *static_cast<RankStressPass*>(self);
  double* volumes = me.forces_.slot_volumes();
  const auto& halo = me.forces_.halo();
  for (std::size_t i = 0; i < halo.size(); ++i) {
    double* out = me.send_[i].data();
    for (std::uint32_t s : halo[i].send) *out++ = volumes[s];
    me.anp_doubles_sent_ += static_cast<double>(halo[i].send.size()), ++me.anp_messages_sent_;
    check(MPI_Irecv(me.receive_[i].data(), static_cast<int>(halo[i].receive.size()), MPI_DOUBLE, halo[i].rank, 1, me.comm_, &me.requests_[2 * i]),
          "MPI_Irecv");
    check(MPI_Isend(me.send_[i].data(), static_cast<int>(halo[i].send.size()), MPI_DOUBLE, halo[i].rank, 1, me.comm_, &me.requests_[2 * i + 1]),
          "MPI_Isend");
  }
  check(MPI_Waitall(static_cast<int>(me.requests_.size()), me.requests_.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
  for (std::size_t i = 0; i < halo.size(); ++i) {
    const double* in = me.receive_[i].data();
    for (std::uint32_t s : halo[i].receive) volumes[s] = *in++;
  }
}

// The master thread, after each node pass of the ANP J pass: the values of the nodes this rank
// owns that others read, out; those of its ghost nodes, in (blocking).
void RankStressPass::exchange_nodes(void* self, double* values) {
  auto& me = *static_cast<RankStressPass*>(self);
  const auto& ghosts = me.forces_.anp_ghosts();
  me.anp_doubles_sent_ += static_cast<double>(me.exchange_ghosts(ghosts, me.anp_ghost_buffers_, values, 1, 2));
  me.anp_messages_sent_ += static_cast<double>(ghosts.size());
}

void RankStressPass::GhostBuffers::sized_for(const std::vector<NodeGhosts>& ghosts, std::size_t width) {
  send.clear(), receive.clear();
  for (const NodeGhosts& g : ghosts) send.emplace_back(width * g.send.size()), receive.emplace_back(width * g.receive.size());
  requests.resize(2 * ghosts.size());
}

std::size_t RankStressPass::GhostBuffers::memory_bytes() const {
  std::size_t b = requests.capacity() * sizeof(MPI_Request);
  for (const auto& x : send) b += x.capacity() * sizeof(double);
  for (const auto& x : receive) b += x.capacity() * sizeof(double);
  return b;
}

std::size_t RankStressPass::exchange_ghosts(const std::vector<NodeGhosts>& ghosts, GhostBuffers& buffers, double* values, std::size_t width,
                                            int tag) {
  std::size_t sent = 0;
  for (std::size_t i = 0; i < ghosts.size(); ++i) {
    std::vector<double>& out = buffers.send[i];
    std::vector<double>& in = buffers.receive[i];
    for (std::size_t k = 0; k < ghosts[i].send.size(); ++k)
      std::memcpy(&out[width * k], values + width * static_cast<std::size_t>(ghosts[i].send[k]), width * sizeof(double));
    sent += out.size();
    check(MPI_Irecv(in.data(), static_cast<int>(in.size()), MPI_DOUBLE, ghosts[i].rank, tag, comm_, &buffers.requests[2 * i]), "MPI_Irecv");
    check(MPI_Isend(out.data(), static_cast<int>(out.size()), MPI_DOUBLE, ghosts[i].rank, tag, comm_, &buffers.requests[2 * i + 1]), "MPI_Isend");
  }
  check(MPI_Waitall(static_cast<int>(buffers.requests.size()), buffers.requests.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
  for (std::size_t i = 0; i < ghosts.size(); ++i)
    for (std::size_t k = 0; k < ghosts[i].receive.size(); ++k)
      std::memcpy(values + width * static_cast<std::size_t>(ghosts[i].receive[k]), &buffers.receive[i][width * k], width * sizeof(double));
  return sent;
}

StressPassResult RankStressPass::compute(const double* u, const double* v, double* f_out, StressSideTask side) {
  return pass_and_gather(u, v, f_out, side, false);
}

StressPassResult RankStressPass::compute_everywhere(const double* u, const double* v, double* f_out, StressSideTask side) {
  return pass_and_gather(u, v, f_out, side, true);
}

// The pass, then one MPI_Allgatherv per pass of what every rank needs from every other, each
// rank's in a fixed layout (Gather): its exact sums, its minima and, for the integrator, the
// forces of its owned nodes that every rank integrates. One collective rather than three: each costs a synchronisation of the
// ranks, and on the hand-block the three cost more than their bytes.
StressPassResult RankStressPass::pass_and_gather(const double* u, const double* v, double* f_out, StressSideTask side, bool everywhere) {
  const StressPassResult local =
      forces_.compute(u, v, f_out, side, StressExchange{&start_exchange, &finish_exchange, &exchange_volumes, &exchange_nodes, this});
  const double start = MPI_Wtime();
  ++passes_;
  // The sums: this rank's exact accumulators, as words (bit for bit in the doubles' slots).
  records_.clear();
  const PassSums& sums = forces_.pass_sums();
  for (const ExactSum* sum : {&sums.energy, &sums.viscous_power}) {
    const std::array<std::int64_t, ExactSum::kWords> words = sum->words();
    const std::size_t at = records_.size();
    records_.resize(at + words.size());  // within the reserved size: no allocation
    std::memcpy(records_.data() + at, words.data(), sizeof words);
  }
  // The minima, as value-index pairs: the element step and the smallest J, each with its tet, and
  // the nodal bound's largest rows (plain, and per eta of the ANP form), negated; `local` holds
  // this rank's (its atoms alone have results).
  const NodalBoundRows rows = forces_.nodal_bound_rows();
  records_.insert(records_.end(), {local.element_critical_step, static_cast<double>(local.limiting_element), local.min_jacobian,
                                   static_cast<double>(local.min_jacobian_element), -rows.plain, static_cast<double>(rows.plain_node)});
  for (int j = 0; j < NodalBoundRows::kEtas; ++j) records_.insert(records_.end(), {-rows.eta[j], static_cast<double>(rows.eta_node[j])});
  double packing = MPI_Wtime();
  if (everywhere) forces_order_.pack(f_out, rank_, records_);
  packing = MPI_Wtime() - packing;
  const Gather& g = everywhere ? with_forces_ : sums_only_;
  check(MPI_Allgatherv(records_.data(), static_cast<int>(records_.size()), MPI_DOUBLE, gathered_.data(), g.counts.data(), g.offsets.data(),
                       MPI_DOUBLE, comm_),
        "MPI_Allgatherv");
  gather_doubles_sent_ += static_cast<double>(records_.size());
  // The whole model's sums: every rank's words added (integers: exact in any order).
  PassSums whole;
  std::array<std::int64_t, 2 * ExactSum::kWords> words;
  for (std::size_t from = 0; from < g.offsets.size(); ++from) {
    std::memcpy(words.data(), gathered_.data() + g.offsets[from], sizeof words);
    whole.energy.add_words(words.data()), whole.viscous_power.add_words(words.data() + ExactSum::kWords);
  }
  StressPassResult r = forces_.pass_result(whole);
  // Each minimum over the ranks as MPI_MINLOC takes it: the smallest value, ties to the smallest
  // index (for the tets: the first atom's, as the one-process pass takes them; for the rows, the
  // first chunk's). The nodal step then comes from the largest rows as in one process: a MIN of
  // each rank's step would not do, for the ANP form takes, per eta, the largest row over every node
  // first.
  double best[kMinima][2];
  for (std::size_t from = 0; from < g.offsets.size(); ++from) {
    const double* x = gathered_.data() + g.offsets[from] + kSumRecord;  // after the rank's sums
    for (int k = 0; k < kMinima; ++k)
      if (from == 0 || x[2 * k] < best[k][0] || (x[2 * k] == best[k][0] && x[2 * k + 1] < best[k][1]))
        best[k][0] = x[2 * k], best[k][1] = x[2 * k + 1];
  }
  r.element_critical_step = r.critical_step = best[0][0], r.limiting_element = static_cast<std::size_t>(best[0][1]);
  r.min_jacobian = best[1][0], r.min_jacobian_element = static_cast<std::size_t>(best[1][1]);
  if (forces_.nodal_bound_on()) {
    NodalBoundRows all;
    all.plain = -best[2][0], all.plain_node = static_cast<std::size_t>(best[2][1]), all.has_eta = rows.has_eta;
    for (int j = 0; rows.has_eta && j < NodalBoundRows::kEtas; ++j)
      all.eta[j] = -best[3 + j][0], all.eta_node[j] = static_cast<std::size_t>(best[3 + j][1]);
    forces_.nodal_step(all, r);
  }
  if (everywhere) {
    const double unpacking = MPI_Wtime();
    forces_order_.unpack(gathered_.data(), with_forces_.forces_at, rank_, f_out);
    force_gather_seconds_ += packing + MPI_Wtime() - unpacking;
  }
  sums_seconds_ += MPI_Wtime() - start;
  return r;
}

// Who integrates what: a node's owner (the rank of its first atom, whose forces there are whole
// after the halo) integrates it, every rank integrates the `everywhere` nodes (their forces gathered
// to all) and the nodes no stress-pass tet holds (force 0 on every rank). A chunk of the sums over
// dofs (the energy audit's, the relaxation's) goes to the rank that integrates most of its nodes
// alone (ties to the lower rank). A rank then reads, and receives after each update, every node of
// its tets and of its chunks that it does not integrate. Every rank derives every rank's lists from the model, so both sides of an exchange
// agree without a message.
void RankStressPass::step_owned_nodes(const std::vector<char>& everywhere, std::size_t sum_chunk_dofs) {
  const std::vector<std::int32_t>& node_owner = forces_.node_ranks();
  const std::size_t nodes = model_.num_nodes, ndof = 3 * nodes;
  // Per node the one rank that integrates it, or -1 (every rank does).
  std::vector<std::int32_t>& alone = alone_;
  alone.assign(nodes, -1);
  for (std::size_t n = 0; n < nodes; ++n)
    if (!everywhere[n]) alone[n] = node_owner[n];
  integrated_dofs_.clear();
  for (std::size_t n = 0; n < nodes; ++n)
    if (alone[n] < 0 || alone[n] == rank_)
      for (std::uint32_t d = 0; d < 3; ++d) integrated_dofs_.push_back(static_cast<std::uint32_t>(3 * n + d));
  // The chunks: the rank that integrates most of a chunk's nodes alone sums it.
  const std::size_t chunks = (ndof + sum_chunk_dofs - 1) / sum_chunk_dofs;
  std::vector<std::int32_t>& chunk_rank = chunk_rank_;
  chunk_rank.assign(chunks, 0);
  std::vector<std::size_t> count(static_cast<std::size_t>(ranks_));
  auto chunk_nodes = [&](std::size_t c) {
    return std::pair<std::size_t, std::size_t>(c * sum_chunk_dofs / 3, (std::min(ndof, (c + 1) * sum_chunk_dofs) + 2) / 3);
  };
  for (std::size_t c = 0; c < chunks; ++c) {
    std::fill(count.begin(), count.end(), 0);
    const auto [begin, end] = chunk_nodes(c);
    for (std::size_t n = begin; n < end; ++n)
      if (alone[n] >= 0) ++count[static_cast<std::size_t>(alone[n])];
    chunk_rank[c] = static_cast<std::int32_t>(std::max_element(count.begin(), count.end()) - count.begin());
  }
  chunk_mine_.assign(chunks, 0);
  for (std::size_t c = 0; c < chunks; ++c) chunk_mine_[c] = chunk_rank[c] == rank_;
  chunk_orders_.clear();
  // needs[r]: the nodes rank r reads but another integrates alone (ascending, once each).
  std::vector<std::vector<std::uint32_t>> needs(static_cast<std::size_t>(ranks_));
  std::vector<std::int32_t> marked(nodes, -1);
  auto need = [&](std::size_t r, std::size_t n) {
    if (alone[n] < 0 || alone[n] == static_cast<std::int32_t>(r) || marked[n] == static_cast<std::int32_t>(r)) return;
    marked[n] = static_cast<std::int32_t>(r), needs[r].push_back(static_cast<std::uint32_t>(n));
  };
  for (std::size_t r = 0; r < needs.size(); ++r) {
    for (const TetRun& run : tet_runs_)
      if (run.rank == static_cast<std::int32_t>(r))
        for (std::size_t corner = 4 * run.begin; corner < 4 * run.end; ++corner) need(r, static_cast<std::size_t>(model_.conn[corner]));
    for (std::size_t c = 0; c < chunks; ++c)
      if (chunk_rank[c] == static_cast<std::int32_t>(r))
        for (auto [n, end] = chunk_nodes(c); n < end; ++n) need(r, n);
    std::sort(needs[r].begin(), needs[r].end());
  }
  state_ghosts_.clear();
  for (int r = 0; r < ranks_; ++r) {
    if (r == rank_) continue;
    NodeGhosts g;
    g.rank = r;
    for (std::uint32_t n : needs[static_cast<std::size_t>(r)])
      if (alone[n] == rank_) g.send.push_back(n);
    for (std::uint32_t n : needs[static_cast<std::size_t>(rank_)])
      if (alone[n] == r) g.receive.push_back(n);
    if (!g.send.empty() || !g.receive.empty()) state_ghosts_.push_back(std::move(g));
  }
  state_buffers_.sized_for(state_ghosts_, 3);
  nodes_order_.build(alone, ranks_, 3);
  // The pass's gather now carries the everywhere nodes' forces alone.
  std::vector<std::int32_t> gathered_owner(nodes, -1);
  for (std::size_t n = 0; n < nodes; ++n)
    if (everywhere[n]) gathered_owner[n] = node_owner[n];
  forces_order_.build(gathered_owner, ranks_, 3);
  layout_gathers();
}

void RankStressPass::share_ghosts(double* values) {
  ghost_doubles_sent_ += static_cast<double>(exchange_ghosts(state_ghosts_, state_buffers_, values, 3, 3));
  ++ghost_shares_;
}

void RankStressPass::gather_sum_chunks(double* chunks, std::size_t width) {
  if (chunk_orders_.size() <= width) chunk_orders_.resize(width + 1);
  RankOrder& order = chunk_orders_[width];
  if (order.counts.empty()) order.build(chunk_rank_, ranks_, width);  // once per width
  order.gather(chunks, chunks, rank_, comm_);
}

void RankStressPass::gather_some_nodes(const std::vector<std::uint32_t>& nodes, std::initializer_list<double*> arrays) {
  if (integrated_dofs_.empty() || nodes.empty()) return;
  // Each listed node's values travel from the rank that integrates it alone, in list order; every
  // rank knows who that is, so the counts need no message.
  const std::size_t per_node = 3 * arrays.size();
  some_counts_.assign(static_cast<std::size_t>(ranks_), 0), some_offsets_.assign(static_cast<std::size_t>(ranks_), 0);
  for (std::uint32_t n : nodes)
    if (alone_[n] >= 0) some_counts_[static_cast<std::size_t>(alone_[n])] += static_cast<int>(per_node);
  std::exclusive_scan(some_counts_.begin(), some_counts_.end(), some_offsets_.begin(), 0);
  some_mine_.clear();
  for (std::uint32_t n : nodes)
    if (alone_[n] == rank_)
      for (const double* a : arrays)
        some_mine_.insert(some_mine_.end(), a + 3 * static_cast<std::size_t>(n), a + 3 * static_cast<std::size_t>(n) + 3);
  some_all_.resize(static_cast<std::size_t>(some_offsets_.back() + some_counts_.back()));
  check(MPI_Allgatherv(some_mine_.data(), static_cast<int>(some_mine_.size()), MPI_DOUBLE, some_all_.data(), some_counts_.data(),
                       some_offsets_.data(), MPI_DOUBLE, comm_),
        "MPI_Allgatherv");
  std::vector<std::size_t>& at = some_next_;  // per rank where its next node's values are
  at.assign(some_offsets_.begin(), some_offsets_.end());
  for (std::uint32_t n : nodes) {
    if (alone_[n] < 0) continue;
    std::size_t& k = at[static_cast<std::size_t>(alone_[n])];
    for (double* a : arrays) std::memcpy(a + 3 * static_cast<std::size_t>(n), &some_all_[k], 3 * sizeof(double)), k += 3;
  }
}

void RankStressPass::gather_nodes(std::initializer_list<double*> arrays) {
  if (integrated_dofs_.empty()) return;  // every rank steps every node
  for (double* a : arrays) nodes_order_.gather(a, a, rank_, comm_);
}

std::size_t RankStressPass::ghost_doubles() const {
  std::size_t n = 0;
  for (const auto& s : state_buffers_.send) n += s.size();
  return n;
}

void RankStressPass::cell_records(const double* u, const double* v, const CellSink& sink) {
  constexpr int kCellRecordsTag = 4;           // (0-3: the halo and ghost exchanges)
  constexpr std::size_t kMessageTets = 16384;  // records per message: ~1 MB, whatever a rank's share
  std::vector<double> f(3 * model_.num_nodes);
  compute(u, v, f.data());  // the ANP nodal pressures at u
  // On the wire, each tet's four nodes (exact as doubles) then its record: rank 0 holds only its
  // own tets' connectivity too, and writes the cells from them.
  const std::size_t width = cell_record_width(model_), stride = 4 + width;
  std::vector<double> buffer;
  buffer.reserve(stride * std::min(kMessageTets, tets()));
  if (rank_ != 0) {
    const auto send = [&] {
      check(MPI_Send(buffer.data(), static_cast<int>(buffer.size()), MPI_DOUBLE, 0, kCellRecordsTag, comm_), "MPI_Send");
      buffer.clear();
    };
    forces_.cell_records(u, [&](std::size_t, std::size_t, const std::int32_t* nodes, const double* record) {
      for (int k = 0; k < 4; ++k) buffer.push_back(static_cast<double>(nodes[k]));
      buffer.insert(buffer.end(), record, record + width);
      if (buffer.size() == stride * kMessageTets) send();
    });
    if (!buffer.empty()) send();
    return;
  }
  forces_.cell_records(u, sink);
  // Every other rank's records, one rank and one message at a time, in the order of its tets' runs.
  for (int r = 1; r < ranks_; ++r) {
    std::size_t left = rank_tets_[static_cast<std::size_t>(r)], in_buffer = 0;
    const double* at = nullptr;
    for (const TetRun& run : tet_runs_) {
      if (run.rank != r) continue;
      std::size_t block = 0;
      for (std::size_t e = run.begin; e < run.end; ++e, at += stride, --in_buffer, --left) {
        if (in_buffer == 0) {
          in_buffer = std::min(kMessageTets, left);
          buffer.resize(stride * in_buffer);
          check(MPI_Recv(buffer.data(), static_cast<int>(buffer.size()), MPI_DOUBLE, r, kCellRecordsTag, comm_, MPI_STATUS_IGNORE), "MPI_Recv");
          at = buffer.data();
        }
        while (e >= model_.blocks[block].end) ++block;
        const std::int32_t nodes[4] = {static_cast<std::int32_t>(at[0]), static_cast<std::int32_t>(at[1]), static_cast<std::int32_t>(at[2]),
                                       static_cast<std::int32_t>(at[3])};
        sink(block, e, nodes, at + 4);
      }
    }
  }
}

std::array<std::int32_t, 4> RankStressPass::tet_nodes(std::size_t e) {
  std::array<std::int32_t, 4> nodes{-1, -1, -1, -1}, all{};
  if (const std::int32_t* c = forces_.nodes_of_tet(e)) std::copy(c, c + 4, nodes.begin());
  check(MPI_Allreduce(nodes.data(), all.data(), 4, MPI_INT32_T, MPI_MAX, comm_), "MPI_Allreduce");
  return all;
}

StressPassResult RankStressPass::compute_alone(const double* u, const double* v, double* f_out) {
  InternalForces one(model_, beta_, 1);  // this rank's forces_ runs only its atoms
  return one.compute(u, v, f_out);
}

nlohmann::json RankStressPass::report(const std::vector<std::pair<std::string, double>>& measured) {
  std::vector<double> mine{static_cast<double>(tets()), static_cast<double>(halo_doubles()), static_cast<double>(halo_ranks()),
                           static_cast<double>(forces_order_.own_items(rank_))};
  for (const auto& [name, value] : measured) mine.push_back(value);
  mine.push_back(sums_seconds_), mine.push_back(force_gather_seconds_), mine.push_back(resident_bytes("VmHWM:"));
  mine.push_back(passes_ > 0 ? anp_doubles_sent_ / passes_ : 0), mine.push_back(passes_ > 0 ? anp_messages_sent_ / passes_ : 0);
  mine.push_back(static_cast<double>(integrated_nodes())), mine.push_back(ghost_shares_ > 0 ? ghost_doubles_sent_ / ghost_shares_ : 0);
  mine.push_back(resident_bytes("VmRSS:")), mine.push_back(passes_ > 0 ? gather_doubles_sent_ / passes_ : 0);
  std::vector<double> all(mine.size() * static_cast<std::size_t>(ranks_));
  check(MPI_Gather(mine.data(), static_cast<int>(mine.size()), MPI_DOUBLE, all.data(), static_cast<int>(mine.size()), MPI_DOUBLE, 0, comm_),
        "MPI_Gather");
  nlohmann::json out = nlohmann::json::array();
  if (rank_ != 0) return out;
  for (int r = 0; r < ranks_; ++r) {
    const double* x = all.data() + mine.size() * static_cast<std::size_t>(r);
    nlohmann::json j = {{"rank", r},
                        {"tets", static_cast<std::size_t>(x[0])},
                        {"halo_doubles_per_pass", static_cast<std::size_t>(x[1])},
                        {"halo_messages_per_pass", static_cast<std::size_t>(x[2])},
                        {"owned_nodes", static_cast<std::size_t>(x[3])}};
    for (std::size_t k = 0; k < measured.size(); ++k) j[measured[k].first] = x[4 + k];
    j["sums_s"] = x[4 + measured.size()], j["force_gather_s"] = x[5 + measured.size()];
    j["peak_resident_bytes"] = x[6 + measured.size()];
    j["anp_exchange_doubles_per_pass"] = x[7 + measured.size()], j["anp_exchange_messages_per_pass"] = x[8 + measured.size()];
    j["integrated_nodes"] = static_cast<std::size_t>(x[9 + measured.size()]);
    j["ghost_doubles_per_exchange"] = x[10 + measured.size()];
    j["resident_bytes_at_end"] = x[11 + measured.size()];
    j["gather_doubles_per_pass"] = x[12 + measured.size()];
    out.push_back(j);
  }
  return out;
}

}  // namespace tactus::solver
