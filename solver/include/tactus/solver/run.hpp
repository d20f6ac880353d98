#pragma once
// A whole simulation: scenario -> model -> explicit run -> results folder:
//   <out>/results/state_NNNN.vtu   one per output time (deformed geometry; point data
//                                  displacement, velocity; cell data cauchy_stress (xx,yy,zz,xy,yz,xz),
//                                  von_mises, material, body, J, fibre_stretch; with contact, point
//                                  data contact_pressure, contact_traction, contact_status, contact_gap)
//   <out>/results.pvd              ParaView collection of those files with their times
//   <out>/history.csv              step, time, dt, energies (incl. contact work), balance error,
//                                  critical step, contact force/area/peak pressure and where
//   <out>/run.json                 status, steps, dt, limiting element, wall time and its split,
//                                  energy balance, material and body names, contact peaks
// The folder is staged (OutputFolder) and moved into place when the run ends. A numerical failure
// still publishes it, with the last good state written and run.json saying "failed" and why; an
// interrupt publishes nothing (with checkpoints on, it writes one and keeps the staging folder
// for tactus-solve --restart; checkpoint.hpp).
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tactus/core/output.hpp"
#include "tactus/solver/scenario.hpp"
#include "tactus/solver/stress_pass_engine.hpp"

namespace tactus::solver {

struct RunSummary {
  std::string status;  // "completed" or "failed"
  std::size_t steps = 0;
  double end_time = 0, dt_min = 0, dt_max = 0, wall_seconds = 0;
  double energy_balance_error = 0;        // final, J
  double max_relative_balance_error = 0;  // max over steps of |error| / scale
  std::size_t outputs = 0;
  double relaxed_at = -1;              // s: dynamic relaxation ended the run here (-1: it did not; relaxation.hpp)
  std::vector<double> von_mises_peak;  // per material block, over the output states
  // Each restart of this run (tactus-solve --restart): the step and time it continued from.
  std::vector<std::pair<std::size_t, double>> restarts;
  nlohmann::json run_json;  // what run.json holds
};

// This process's part in a run over MPI ranks (tactus-solve under mpirun; docs/design.md,
// "Decomposition into ranks"): every rank builds the model and steps all of it, the stress pass
// spread over the ranks (each runs its atoms, and the forces are gathered), so every rank holds the
// same state at every step; rank 0 alone writes (run_simulation), the others follow
// (follow_simulation). The run's threads per rank: run.threads, or 1 when it is 0.
struct RankRun {
  int rank = 0, ranks = 1;
  // This rank's part of the stress pass over the model (collective).
  std::function<std::unique_ptr<StressPassEngine>(const Model& model, double beta, int threads)> stress_pass;
  // Every rank must continue from rank 0's checkpoint (the step it was written at + 1, or 0 for a
  // run from t = 0): an InputError on every rank otherwise (collective).
  std::function<void(std::size_t restart_step)> check_same_restart;
  // Checkpoints in parts, one per rank (checkpoint.hpp, checkpoint_part): rank 0's `due` on every
  // rank (each step, when the run writes checkpoints), rank 0's text on every rank (the
  // checkpoints' folder, once), and a meeting of every rank (before part 0's manifest). Collective.
  std::function<bool(bool due)> rank0_decides;
  std::function<std::string(const std::string& text)> rank0_text;
  std::function<void()> all_meet;
};

struct RunIdentity;
struct RestartPoint;
// Writes into `out` (checks its free space against the estimated size first) and commits it.
// `identity` goes into its checkpoints (checkpoint.hpp); `from`: continue from that checkpoint
// (in `out`'s staging folder). ranks: rank 0 of a run over ranks (run.json then has "ranks").
RunSummary run_simulation(const Scenario& scenario, OutputFolder& out, const RunIdentity& identity, const RestartPoint* from = nullptr,
                          const RankRun* ranks = nullptr);
// Ranks other than 0: the same model and steps as rank 0's run_simulation, writing nothing, and its
// collectives at the same points. A numerical failure (which every rank meets at the same step) is
// rethrown after the run's last collective.
void follow_simulation(const Scenario& scenario, const RestartPoint* from, const RankRun& ranks);
// The same into a new folder (tests, benchmarks).
RunSummary run_simulation(const Scenario& scenario, const std::filesystem::path& output_dir);
// Every file a scenario reads (the scenario, meshes, fibre files): inputs an output may not replace.
std::vector<std::filesystem::path> scenario_inputs(const Scenario& scenario);

// docs/results-reference.md and .json: every result field, history column and run.json key.
std::string results_reference_markdown();
nlohmann::json results_reference_json();

// The material-point driver (tactus-solve material-point): Cauchy stress against stretch as CSV.
// mode: "uniaxial" (lateral stresses solved to zero), "equibiaxial" (sigma_zz = 0), "shear" (F = I + gamma e_x (x) e_y).
std::string material_point_csv(const Scenario& scenario, const std::string& material, const std::string& mode, double max_value, int samples);

}  // namespace tactus::solver
