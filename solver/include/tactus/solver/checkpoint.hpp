#pragma once
// Restart checkpoints of a run (docs/design.md "Checkpoints and restart").
//
// Where: `<OUT>.partial-<pid>-<token>/checkpoints/checkpoint_<step>.h5`, inside the staging folder of the
// run writing OUT (core/output.hpp), so a killed run and its checkpoints are found from OUT alone.
// The newest two are kept: a new one is written under a temporary name, flushed and renamed
// (core/state_file.hpp) before the older goes, so a complete one is on the disk at every moment.
// What: the integrator's and the contact solver's state (ExplicitSolver::checkpoint), the run
// loop's bookkeeping (history length, states written, peaks) and the run's identity below.
//
// `tactus-solve --restart OUT` takes the newest checkpoint that reads back whole (a corrupt or
// truncated one is named in a warning and the one before it is used), truncates the history to
// the checkpoint's row, and steps on: the finished folder holds the same results and history, bit
// for bit, as an uninterrupted run of the same binary.
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>

#include "tactus/core/state_file.hpp"
#include "tactus/solver/scenario.hpp"

namespace tactus::solver {

inline constexpr const char* kCheckpointKind = "tactus-solve checkpoint";

// What a checkpoint must match to be continued: the same scenario, mesh folder and end time, the
// same bytes in every input file, and the same tactus.
struct RunIdentity {
  std::string scenario;       // absolute path
  std::string meshes;         // tactus-solve --meshes (absolute), or ""
  double end_time = 0;        // the run's end time (after --end-time)
  std::string inputs_digest;  // of the scenario, meshes and fibre files
  std::string version;
  void io(StateArchive& archive);
};
RunIdentity run_identity(const Scenario& scenario, const std::filesystem::path& mesh_dir);

struct RestartPoint {
  std::filesystem::path staging;  // the interrupted run's staging folder
  std::filesystem::path file;     // the checkpoint
  StateArrays state;
  RunIdentity identity;
  std::size_t step = 0;
  double time = 0;
};

// The newest checkpoint that reads back whole over the interrupted tactus-solve runs that were
// writing `output` (staging folders of processes that are gone). A checkpoint that does not read
// back is named in a warning and the one before it is tried. None: std::nullopt.
std::optional<RestartPoint> find_restart_point(const std::filesystem::path& output);

// InputError when `point` cannot continue a run of `identity` (another scenario or end time, a
// changed input, another tactus), naming what differs.
void check_restart_identity(const RestartPoint& point, const RunIdentity& identity);

// What a solve is asked to do (tactus-solve's command line): a scenario into an output folder,
// or `restart`: continue the killed run writing that folder (its scenario, meshes and end time
// come from its checkpoint); `resume`: continue a killed run of the same inputs when there is one.
struct SolveRequest {
  std::filesystem::path scenario, meshes, output, restart;
  std::optional<double> end_time;  // --end-time: later output times are dropped
  bool resume = false;
};
// The run a request comes to: the scenario read (end time applied), where it goes, its identity
// and the checkpoint it continues from, if any. Refuses (InputError) a restart with more than the
// folder, a folder with nothing to continue, a checkpoint of other inputs; a resume whose
// checkpoint does not match starts from t = 0 with a warning.
struct PreparedRun {
  Scenario scenario;
  std::filesystem::path scenario_file, output;
  RunIdentity identity;
  std::optional<RestartPoint> from;
};
PreparedRun prepare_run(SolveRequest request);

}  // namespace tactus::solver
