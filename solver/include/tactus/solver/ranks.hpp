#pragma once
// The stress pass over MPI ranks (docs/design.md, "Decomposition into ranks"; built with
// -DTACTUS_MPI=ON): each rank runs the atoms a Decomposition gives it, sends the slots of the nodes
// it shares to the ranks that share them (non-blocking, while its interior atoms run), and sums
// every node it touches over all the node's slots in atom order, so its forces are the bits of one
// process at any rank count. Each rank's exact sums of its atoms' energies and viscous powers
// (ExactSum) are gathered and added on every rank; the element step, the smallest J and the nodal
// step bound are one global MINLOC. For the integrator (StressPassEngine) the forces of the shared
// nodes, which every rank integrates, are gathered from the ranks that own them (those whose first
// atom is theirs); each rank integrates those and its own (owned-node stepping), and receives the
// other nodes it reads after each update. Every rank builds the whole model for now (scattering it is
// a later step; its pass holds its own tets' geometry, and the model's is released after the
// restart check); the ANP blocks' J pass runs over each rank's own
// nodes, with the volumes at shared nodes and the ghost nodes' values exchanged (InternalForces::anp_ghosts).
#include <mpi.h>

#include <vector>

#include "tactus/solver/decomposition.hpp"
#include "tactus/solver/internal_force.hpp"
#include "tactus/solver/stress_pass_engine.hpp"

namespace tactus::solver {

class RankStressPass : public StressPassEngine {
 public:
  // Collective over comm; d: the same decomposition (atoms of kAtomTets tets) on every rank.
  RankStressPass(const Model& model, const Decomposition& d, MPI_Comm comm, double beta, int threads);
  // f_out (3 per node of the model): right at the nodes touched() by this rank's atoms (those a
  // stress-pass tet of them holds). The result is the whole model's, the same bits on every rank
  // and at any rank count. Collective.
  StressPassResult compute(const double* u, const double* v, double* f_out) { return compute(u, v, f_out, StressSideTask{}); }
  StressPassResult compute(const double* u, const double* v, double* f_out, StressSideTask side);
  // compute, with every rank's owned nodes' forces to every rank in the same Allgatherv (3 doubles
  // per node, in rank then node order): f_out right at every node. Collective.
  StressPassResult compute_everywhere(const double* u, const double* v, double* f_out, StressSideTask side) override;
  void set_nodal_step_bound(const double* nodal_mass) override { forces_.set_nodal_step_bound(nodal_mass); }
  void enable_mass_scaling() override;
  // An MPI_Allgatherv of the tets each rank raised (8 doubles each), merged in tet order; an
  // MPI_MINLOC of each rank's smallest step and its tet; an MPI_Gatherv of the factors to rank 0.
  std::vector<FloorTet> raise_to_floor(double floor2) override;
  std::pair<double, std::size_t> smallest_scaled_step(double beta) override;
  std::vector<double> mass_factors_everywhere() override;
  void set_mass_factors(const std::vector<double>& whole) override { forces_.set_mass_factors(whole); }
  void set_threads(int threads) override { forces_.set_threads(threads); }
  int threads() const override { return forces_.threads(); }
  nlohmann::json report(const std::vector<std::pair<std::string, double>>& measured) override;
  std::size_t memory_bytes() const override;
  std::vector<std::uint32_t> checkpoint_nodes() const override;
  const std::vector<char>& touched() const { return forces_.touched(); }
  StressPassResult compute_alone(const double* u, const double* v, double* f_out) override;
  void step_owned_nodes(const std::vector<char>& everywhere, std::size_t sum_chunk_dofs) override;
  const std::vector<std::uint32_t>& integrated_dofs() const override { return integrated_dofs_; }
  void share_ghosts(double* values) override;
  const char* sum_chunks_summed_here() const override { return chunk_mine_.empty() ? nullptr : chunk_mine_.data(); }
  void gather_sum_chunks(double* chunks, std::size_t width) override;
  void gather_some_nodes(const std::vector<std::uint32_t>& nodes, std::initializer_list<double*> arrays) override;
  void gather_nodes(std::initializer_list<double*> arrays) override;
  bool holds_own_geometry() const override { return true; }
  void cell_records(const double* u, const double* v, const CellSink& sink) override;
  std::array<std::int32_t, 4> tet_nodes(std::size_t e) override;
  // Owned-node stepping: the nodes this process integrates, and the doubles it sends in one
  // share_ghosts.
  std::size_t integrated_nodes() const { return integrated_dofs_.size() / 3; }
  std::size_t ghost_doubles() const;
  int rank() const { return rank_; }
  int ranks() const override { return ranks_; }
  std::size_t tets() const { return rank_tets_[static_cast<std::size_t>(rank_)]; }  // this rank's
  // Doubles sent to other ranks per pass (the halo's size), and the messages: one per rank that
  // shares a node with this one.
  std::size_t halo_doubles() const;
  std::size_t halo_ranks() const { return send_.size(); }
  // Bytes of the per-atom records (energy, viscous power) every rank receives per pass.
  std::size_t gathered_bytes() const;

 private:
  static void start_exchange(void* self);
  static void finish_exchange(void* self);
  static void exchange_volumes(void* self);
  static void exchange_nodes(void* self, double* values);
  const Model& model_;
  double beta_;
  MPI_Comm comm_;
  int rank_ = 0, ranks_ = 1;
  InternalForces forces_;
  std::vector<std::vector<double>> send_, receive_;
  std::vector<MPI_Request> requests_;
  // One exchange of node values with the ranks of a ghost list (NodeGhosts): per pair the values
  // sent and received, and the requests. sized_for: `width` doubles per listed node.
  struct GhostBuffers {
    std::vector<std::vector<double>> send, receive;
    std::vector<MPI_Request> requests;
    void sized_for(const std::vector<NodeGhosts>& ghosts, std::size_t width);
    std::size_t memory_bytes() const;
  };
  // Sends the listed nodes' values (width doubles each, from `values`) to each pair's rank and puts
  // what it receives into `values` (blocking; tag apart per kind of exchange). Returns the doubles sent.
  std::size_t exchange_ghosts(const std::vector<NodeGhosts>& ghosts, GhostBuffers& buffers, double* values, std::size_t width, int tag);
  GhostBuffers anp_ghost_buffers_;  // per InternalForces::anp_ghosts() pair, 1 double per node
  // The ANP J pass's exchanges (volumes and ghost nodes): doubles and messages sent, over passes.
  double anp_doubles_sent_ = 0, anp_messages_sent_ = 0, passes_ = 0;
  double gather_doubles_sent_ = 0;  // in the pass's one gather (its sums, minima and forces), over passes
  // The pass's one gather (pass_and_gather): per rank its doubles and where they land (fixed), and
  // where its owned nodes' forces begin; without the forces (compute) and with them
  // (compute_everywhere). This rank's records, everyone's.
  static constexpr int kMinima = 3 + NodalBoundRows::kEtas;  // value-index pairs
  struct Gather {
    std::vector<int> counts, offsets;
    std::vector<std::size_t> forces_at;
  };
  Gather sums_only_, with_forces_;
  std::vector<double> records_, gathered_;
  StressPassResult pass_and_gather(const double* u, const double* v, double* f_out, StressSideTask side, bool everywhere);
  std::vector<std::size_t> rank_tets_;  // each rank's tets (the runs of tet_runs_ that are its)
  // Values of items (nodes, tets) that each rank has right for its own items, sent to every rank:
  // the items in rank then item order, each rank's doubles and where they land, and for gather
  // (not pack and unpack, whose gather carries more) this rank's values packed and everyone's
  // (`width` doubles per item, sized at its first call). Fixed once built.
  struct RankOrder {
    std::size_t width = 1;
    std::vector<std::uint32_t> items;
    std::vector<int> counts, offsets;
    std::vector<double> mine, all;
    // item_rank: per item its rank, or -1 (an item no rank sends).
    void build(const std::vector<std::int32_t>& item_rank, int ranks, std::size_t width);
    // One MPI_Allgatherv: this rank's items' values from `from` (width per item, by item index) to
    // every rank, each into `to` at its item (collective).
    void gather(const double* from, double* to, int rank, MPI_Comm comm);
    // The same in pieces, for a gather that carries more: this rank's items' values appended to
    // `out`; every other rank's from `all_ranks`, rank r's from rank_at[r], into `to`.
    void pack(const double* from, int rank, std::vector<double>& out) const;
    void unpack(const double* all_ranks, const std::vector<std::size_t>& rank_at, int rank, double* to) const;
    std::size_t own_items(int rank) const { return static_cast<std::size_t>(counts[static_cast<std::size_t>(rank)]) / width; }
    std::size_t memory_bytes() const;
  };
  RankOrder forces_order_;  // the nodes each rank owns (InternalForces::node_ranks), 3 doubles each
  // The tets' ranks as runs of consecutive tets of one rank (the decomposition's atoms, a rank's
  // adjacent ones merged: a few per atom, not one per tet). Mass scaling: the tets' order (1 double
  // each, built when scaling is on), and every tet's step.
  struct TetRun {
    std::size_t begin, end;
    std::int32_t rank;
  };
  std::vector<TetRun> tet_runs_;
  // Owned-node stepping (step_owned_nodes): the dofs this process integrates; per other process the
  // nodes it sends after each update and those it receives (3 doubles each); the chunks of the sums
  // over dofs summed here and their order; the non-everywhere nodes by owner, for
  // gather_nodes; the doubles sent by share_ghosts over its calls.
  std::vector<std::uint32_t> integrated_dofs_;
  std::vector<NodeGhosts> state_ghosts_;
  GhostBuffers state_buffers_;
  std::vector<std::int32_t> alone_;       // per node the one rank that integrates it, or -1: every rank
  std::vector<std::int32_t> chunk_rank_;  // per chunk of the sums over dofs the rank that sums it
  std::vector<char> chunk_mine_;
  std::vector<RankOrder> chunk_orders_;  // per width (doubles per chunk), built when first gathered
  RankOrder nodes_order_;
  std::vector<int> some_counts_, some_offsets_;  // gather_some_nodes's layout and values (reused)
  std::vector<double> some_mine_, some_all_;
  std::vector<std::size_t> some_next_;
  double ghost_doubles_sent_ = 0, ghost_shares_ = 0;
  void layout_gathers();  // sums_only_ and with_forces_ from the sums, the minima and forces_order_
  // Wall time from the end of the pass to the result (the gather, its waiting and the sums), and of
  // it the forces' packing and unpacking (compute_everywhere).
  double sums_seconds_ = 0, force_gather_seconds_ = 0;
};

}  // namespace tactus::solver

#include <filesystem>

#include "tactus/solver/run.hpp"

namespace tactus::solver {

// True when mpirun (Open MPI) started this process: its environment says so.
bool started_by_mpirun();

// MPI for one tactus-solve process under mpirun: MPI_Init_thread (FUNNELED: only the master
// thread calls MPI, inside the stress pass) and MPI_Finalize.
class RankSession {
 public:
  RankSession(int* argc, char*** argv);
  ~RankSession();
  RankSession(const RankSession&) = delete;
  RankSession& operator=(const RankSession&) = delete;
  int rank() const { return rank_; }
  int ranks() const { return ranks_; }
  // The build-hash handshake (collective): an InputError on every rank naming the first rank
  // whose executable's bytes differ from rank 0's (mismatched binaries across machines).
  void check_same_build() const;
  // Ends every rank's process (MPI_Abort) with this exit code.
  [[noreturn]] void abort(int code) const;
  // After this process's run failed: true when every rank reaches this call within `seconds` (the
  // failure was the same everywhere, at the same point: each may finalize and exit), false when
  // one does not (it runs on, or waits in a collective this process left: abort). On a
  // communicator of its own, so it cannot match a collective of the run.
  bool all_stopped_within(double seconds) const;
  // The RankRun of a run: the model's atoms (kAtomTets) cut by METIS into ranks() parts, or read
  // from `partition` (decomposition.hpp, read_partition) when given; more ranks than tets / 8, or
  // than atoms, is refused naming the limit. Every rank decomposes alike (METIS with a fixed seed):
  // a checksum of the parts across ranks makes sure.
  RankRun run(const std::filesystem::path& partition) const;

 private:
  int rank_ = 0, ranks_ = 1;
  MPI_Comm stop_comm_ = MPI_COMM_NULL;
};

}  // namespace tactus::solver
