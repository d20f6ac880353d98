#pragma once
// The stress pass as the explicit integrator calls it: this process's (OneProcessStressPass, over
// InternalForces) or one spread over MPI ranks (RankStressPass, ranks.hpp). Either gives, every
// step, what InternalForces::compute gives one process - the internal forces at every node and the
// whole model's sums and minima - with the same bits, so that every process of a run over ranks
// goes on with the same state (docs/design.md, "tactus-solve under mpirun"). The solver library
// itself needs no MPI: only this interface.
#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "tactus/solver/internal_force.hpp"

namespace tactus::solver {

class StressPassEngine {
 public:
  virtual ~StressPassEngine() = default;
  // f_out (3 per node of the model) at every node, and the whole model's result: the bits of one
  // process's InternalForces::compute. On ranks collective: every process calls it at the same step.
  virtual StressPassResult compute_everywhere(const double* u, const double* v, double* f_out, StressSideTask side) = 0;
  // The same pass by this process alone, not collective (a restored state's check, once).
  virtual StressPassResult compute_alone(const double* u, const double* v, double* f_out) = 0;
  virtual void set_nodal_step_bound(const double* nodal_mass) = 0;  // as InternalForces::set_nodal_step_bound
  // Mass scaling (as InternalForces's; each process holds the mass factors of its own tets): the
  // tets of the last pass below the floor (floor2: its square), raised to meet it, every process's
  // in tet order; the smallest step with the factors as they are then, and its tet; every tet's
  // factor (a checkpoint's; set_mass_factors keeps this process's own of them). On ranks
  // collective (raise_to_floor and smallest_scaled_step only when the run scales, which every
  // process knows alike): each rank scans its own tets and sends the others what it raised, a few
  // tets a step rather than every tet's step; the factors are gathered to rank 0 (empty elsewhere).
  virtual void enable_mass_scaling() = 0;
  virtual std::vector<FloorTet> raise_to_floor(double floor2) = 0;
  virtual std::pair<double, std::size_t> smallest_scaled_step(double beta) = 0;
  virtual std::vector<double> mass_factors_everywhere() = 0;
  virtual void set_mass_factors(const std::vector<double>& whole) = 0;
  virtual void set_threads(int threads) = 0;
  virtual int threads() const = 0;
  virtual int ranks() const = 0;
  // What each process did (on ranks collective; the array on rank 0, empty elsewhere; null for one
  // process): per rank its tets, halo doubles and messages per pass, its owned nodes, `measured` (its
  // wall times and data structures' bytes, by name) and the pass's own (RankStressPass: sums_s, its one gather of sums,
  // minima and forces; force_gather_s, of that the forces' packing; peak_resident_bytes, the
  // process's peak memory).
  virtual nlohmann::json report(const std::vector<std::pair<std::string, double>>& measured) = 0;
  virtual std::size_t memory_bytes() const = 0;
  // The nodes whose per-node state this process writes in its checkpoint part (checkpoint.hpp):
  // one process, every node; on ranks those it owns (rank 0 also those no stress-pass tet holds).
  virtual std::vector<std::uint32_t> checkpoint_nodes() const = 0;

  // Owned-node stepping (ranks; docs/design.md, "tactus-solve under mpirun"). One process steps
  // every node and these do nothing. On ranks, step_owned_nodes (collective, once, before the first
  // pass) makes each process integrate only the nodes it owns and the `everywhere` ones (1 per node:
  // contact, rigid, supported and loaded nodes, which every process integrates alike from the same
  // forces): from then on compute_everywhere gathers only the everywhere nodes' forces, and the
  // integrator calls share_ghosts after each update, so that every node a process reads (its tets'
  // and those of the chunks of the sums over dofs it sums) holds its integrator's value.
  // sum_chunk_dofs: a chunk's dofs (ChunkShare, energy.hpp).
  virtual void step_owned_nodes(const std::vector<char>& /*everywhere*/, std::size_t /*sum_chunk_dofs*/) {}
  // The dofs this process integrates, ascending; empty: every dof.
  virtual const std::vector<std::uint32_t>& integrated_dofs() const { return no_dofs_; }
  // Collective: 3 values per node (u or v), the nodes this process reads but does not integrate
  // from the processes that do.
  virtual void share_ghosts(double* /*values*/) {}
  // The chunks of the sums over dofs (ChunkShare, energy.hpp) this process sums (1 each), or null:
  // all. gather_sum_chunks (collective) then fills every other chunk's `width` doubles from the
  // process that summed it.
  virtual const char* sum_chunks_summed_here() const { return nullptr; }
  virtual void gather_sum_chunks(double* /*chunks*/, std::size_t /*width*/) {}
  // Collective: 3 values per listed node (the same list on every process, ascending) of each array
  // from the process that integrates it (mass scaling's newly raised nodes, whose added kinetic
  // energy is booked in node order).
  virtual void gather_some_nodes(const std::vector<std::uint32_t>& /*nodes*/, std::initializer_list<double*> /*arrays*/) {}
  // Collective: every node's 3 values of each array from the process that integrates it, so that
  // every process holds the whole state (before a state file or the last good state is written).
  virtual void gather_nodes(std::initializer_list<double*> /*arrays*/) {}
  // On ranks the pass reads its own tets' geometry from its own copy (InternalForces::
  // hold_own_geometry), so the model's may be released once the restart check has run; one
  // process reads the model's.
  virtual bool holds_own_geometry() const { return false; }
  // The state files' cell records at u (cell_record_width doubles per tet: internal_force.hpp),
  // after a pass at u (v: its viscous part, not reported), each handed to sink with its block and
  // tet. On ranks collective: every rank computes its own tets' and rank 0 receives them, rank by
  // rank; sink is called on rank 0 only.
  virtual void cell_records(const double* u, const double* v, const CellSink& sink) = 0;
  // Tet e's four nodes (a message's: the tet an error names). On ranks collective: from the rank
  // that holds them, since no rank need hold every tet's.
  virtual std::array<std::int32_t, 4> tet_nodes(std::size_t e) = 0;

 private:
  std::vector<std::uint32_t> no_dofs_;
};

// One process: InternalForces as it is.
class OneProcessStressPass final : public StressPassEngine {
 public:
  OneProcessStressPass(const Model& model, double beta, int threads) : forces_(model, beta, threads), nodes_(model.num_nodes) {}
  StressPassResult compute_everywhere(const double* u, const double* v, double* f_out, StressSideTask side) override {
    return forces_.compute(u, v, f_out, side);
  }
  StressPassResult compute_alone(const double* u, const double* v, double* f_out) override { return forces_.compute(u, v, f_out); }
  void set_nodal_step_bound(const double* nodal_mass) override { forces_.set_nodal_step_bound(nodal_mass); }
  void enable_mass_scaling() override { forces_.enable_mass_scaling(); }
  std::vector<FloorTet> raise_to_floor(double floor2) override {
    std::vector<FloorTet> below;
    forces_.raise_to_floor(floor2, below);
    return below;
  }
  std::vector<double> mass_factors_everywhere() override { return forces_.mass_factors(); }
  void set_mass_factors(const std::vector<double>& whole) override { forces_.set_mass_factors(whole); }
  std::pair<double, std::size_t> smallest_scaled_step(double beta) override { return forces_.smallest_scaled_step(beta); }
  void set_threads(int threads) override { forces_.set_threads(threads); }
  int threads() const override { return forces_.threads(); }
  int ranks() const override { return 1; }
  nlohmann::json report(const std::vector<std::pair<std::string, double>>&) override { return nullptr; }
  std::size_t memory_bytes() const override { return forces_.memory_bytes(); }
  void cell_records(const double* u, const double* v, const CellSink& sink) override {
    std::vector<double> f(3 * nodes_);
    forces_.compute(u, v, f.data());
    forces_.cell_records(u, sink);
  }
  std::array<std::int32_t, 4> tet_nodes(std::size_t e) override {
    const std::int32_t* c = forces_.nodes_of_tet(e);
    return {c[0], c[1], c[2], c[3]};
  }
  std::vector<std::uint32_t> checkpoint_nodes() const override {
    std::vector<std::uint32_t> all(nodes_);
    std::iota(all.begin(), all.end(), std::uint32_t{0});
    return all;
  }

 private:
  InternalForces forces_;
  std::size_t nodes_;
};

}  // namespace tactus::solver
