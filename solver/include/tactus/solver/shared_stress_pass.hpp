#pragma once
// The seam between the explicit integrator and a stress pass spread over processes (MPI ranks:
// RankStressPass, ranks.hpp). The integrator asks it, every step, for what InternalForces::compute
// gives one process - the internal forces at every node and the whole model's sums and minima -
// with the same bits, so that every process can go on with the same state (docs/design.md,
// "Decomposition into ranks"). The solver library itself needs no MPI: only this interface.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tactus/solver/internal_force.hpp"

namespace tactus::solver {

class SharedStressPass {
 public:
  virtual ~SharedStressPass() = default;
  // f_out (3 per node of the model) at every node, and the whole model's result: the bits of one
  // process's InternalForces::compute. Collective: every process calls it at the same step.
  virtual StressPassResult compute_everywhere(const double* u, const double* v, double* f_out, StressSideTask side) = 0;
  virtual void set_nodal_step_bound(const double* nodal_mass) = 0;  // as InternalForces::set_nodal_step_bound
  // Mass scaling (as InternalForces's): the per-tet mass factors, the same on every process (each
  // raises them alike from the same steps), and every tet's unscaled squared step of the last pass,
  // gathered to every process (collective: only when the run scales, which every process knows alike).
  virtual void enable_mass_scaling() = 0;
  virtual std::vector<double>& mass_factor() = 0;
  virtual const std::vector<double>& element_dt2_everywhere() = 0;
  virtual void set_threads(int threads) = 0;
  virtual int threads() const = 0;
  virtual int rank() const = 0;
  virtual int ranks() const = 0;
  // What each process did (collective; the array on rank 0, empty elsewhere): per rank its tets,
  // halo doubles and messages per pass, its owned nodes, `seconds` (its measured wall times by name)
  // and the pass's own (RankStressPass: sums_s, the sums' gather and MINLOC; force_gather_s;
  // peak_resident_bytes, the process's peak memory).
  virtual nlohmann::json report(const std::vector<std::pair<std::string, double>>& seconds) = 0;
  virtual std::size_t memory_bytes() const = 0;
};

}  // namespace tactus::solver
