#pragma once
// The stress pass over MPI ranks (docs/design.md, "Decomposition into ranks"; built with
// -DTACTUS_MPI=ON): each rank runs the atoms a Decomposition gives it, sends the slots of the nodes
// it shares to the ranks that share them (non-blocking, while its interior atoms run), and sums
// every node it touches over all the node's slots in atom order, so its forces are the bits of one
// process at any rank count. The per-atom energies and viscous powers are gathered and added in
// atom order on every rank; the element step, the smallest J and the nodal step bound are one
// global MINLOC. Every rank holds the whole model
// for now (scattering it is the next step), and ANP blocks are refused (their J pass needs a
// second exchange).
#include <mpi.h>

#include <vector>

#include "tactus/solver/decomposition.hpp"
#include "tactus/solver/internal_force.hpp"

namespace tactus::solver {

class RankStressPass {
 public:
  // Collective over comm; d: the same decomposition (atoms of kAtomTets tets) on every rank.
  RankStressPass(const Model& model, const Decomposition& d, MPI_Comm comm, double beta, int threads);
  // f_out (3 per node of the model): right at the nodes touched() by this rank's atoms. The result
  // is the whole model's, the same bits on every rank and at any rank count. Collective.
  StressPassResult compute(const double* u, const double* v, double* f_out);
  const std::vector<char>& touched() const { return touched_; }
  int rank() const { return rank_; }
  // Doubles sent to other ranks per pass (the halo's size), and the messages: one per rank that
  // shares a node with this one.
  std::size_t halo_doubles() const;
  std::size_t halo_ranks() const { return send_.size(); }
  // Bytes of the per-atom records (energy, viscous power) every rank receives per pass.
  std::size_t gathered_bytes() const;

 private:
  static void start_exchange(void* self);
  static void finish_exchange(void* self);
  MPI_Comm comm_;
  int rank_ = 0, ranks_ = 1;
  InternalForces forces_;
  std::vector<char> touched_;
  std::vector<std::vector<double>> send_, receive_;
  std::vector<MPI_Request> requests_;
  // The sums' gather: counts and offsets per rank (fixed), this rank's records, everyone's.
  std::vector<int> counts_, offsets_;
  std::vector<double> records_, gathered_;
  std::vector<StressAccumulator> atoms_;  // every atom's sums
  std::vector<std::size_t> next_;
};

}  // namespace tactus::solver
