#pragma once
// Restart checkpoints of a run (docs/design.md "Checkpoints and restart").
//
// Where: `<OUT>.partial-<pid>-<token>/checkpoints/`, inside the staging folder of the run writing
// OUT (core/output.hpp), so a killed run and its checkpoints are found from OUT alone. A checkpoint
// is its state in parts, `checkpoint_<step>.part<k>of<n>.h5` (one part per process of the run: one
// in one process, one per MPI rank under mpirun, checkpoint_part), and a manifest,
// `checkpoint_<step>.json`, written last, naming the parts and their sizes: a checkpoint is
// complete exactly when its manifest is there
// (CheckpointStore). Each file is written under a temporary name, flushed and renamed
// (core/state_file.hpp); the newest two complete ones are kept, the older removed only after the
// new manifest has its name, so a complete one is on the disk at every moment.
// What: the integrator's and the contact solver's state (ExplicitSolver::checkpoint), the run
// loop's bookkeeping (history length, states written, peaks) and the run's identity below.
//
// `tactus-solve --restart OUT` takes the newest checkpoint that reads back whole (a corrupt or
// truncated one is named in a warning and the one before it is used), truncates the history to
// the checkpoint's row, and steps on: the finished folder holds the same results and history, bit
// for bit, as an uninterrupted run of the same binary.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

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
  std::vector<std::string> overrides;  // tactus-solve --set, in order
  void io(StateArchive& archive);
};
RunIdentity run_identity(const Scenario& scenario, const std::filesystem::path& mesh_dir);

// One complete checkpoint on the disk, as its manifest lists it.
struct CheckpointListing {
  std::size_t step = 0;
  double time = 0;
  std::filesystem::path manifest;
  std::vector<std::filesystem::path> parts;  // part k of parts.size(), in order
};

// The checkpoints of one run (its staging folder's checkpoints/), written part by part.
class CheckpointStore {
 public:
  // This process writes part `part` of `parts` (0 of 1 for a run in one process).
  explicit CheckpointStore(std::filesystem::path folder, int part = 0, int parts = 1);
  const std::filesystem::path& folder() const { return folder_; }
  // Writes this process's part of the checkpoint of `step` (time t); part 0 then writes the
  // manifest (with several parts: once every part is on the disk) and keeps the newest `keep`
  // complete checkpoints, removing the older and any incomplete one before the newest. `phase` is
  // told each stage of the write (write_state_file's, then "manifest" before the manifest goes
  // down): the points where the restart tests kill the process. Returns the manifest's path.
  // all_parts_written (part 0 of several): returns once every other part is on the disk (the
  // ranks meet there before the manifest goes down).
  std::filesystem::path write(std::size_t step, double time, const StateArrays& part, const std::function<void(const char*)>& phase = {},
                              std::size_t keep = 2, const std::function<void()>& all_parts_written = {}) const;

 private:
  std::filesystem::path folder_;
  int part_, parts_;
};

// A run over MPI ranks writes one part per rank: each rank the integrator's per-node arrays
// (kCheckpointNodeArrays: displacements, velocities, forces, masses) at the nodes it owns, listed in
// "part.nodes", and part 0 everything else too. Every rank holds the whole state today; the parts
// are the form a rank that holds only its own nodes writes, and a restart at any rank count reads
// them all back into one state (merge_checkpoint_parts).
extern const std::vector<std::string> kCheckpointNodeArrays;
// The part of `whole` (a checkpoint of a model of num_nodes nodes) that holds `nodes`; `first`:
// part 0, which holds every other array as well.
StateArrays checkpoint_part(const StateArrays& whole, const std::vector<std::uint32_t>& nodes, std::size_t num_nodes, bool first);
// The whole checkpoint from its parts (in part order; `files` name them in errors): part 0's arrays
// with each per-node array put together from every part. InputError naming the part when a node
// is missing, listed twice or out of range, or an array's size does not match its nodes.
StateArrays merge_checkpoint_parts(std::vector<StateArrays> parts, const std::vector<std::filesystem::path>& files);

// The complete checkpoints in `folder` (a manifest whose parts are all there with their sizes),
// newest (highest step) first; a manifest that does not parse or whose parts are missing is
// named in a warning and left out.
std::vector<CheckpointListing> list_checkpoints(const std::filesystem::path& folder);

struct RestartPoint {
  std::filesystem::path staging;  // the interrupted run's staging folder
  std::filesystem::path file;     // the checkpoint's (first) part
  StateArrays state;
  RunIdentity identity;
  std::size_t step = 0;
  double time = 0;
};

// The newest checkpoint that reads back whole over the interrupted tactus-solve runs that were
// writing `output` (staging folders of processes that are gone). A checkpoint that does not read
// back is named in a warning and the one before it is tried. None: std::nullopt.
// probe_locks: as resumable_staging's (false: a rank other than 0 of a run over MPI ranks).
std::optional<RestartPoint> find_restart_point(const std::filesystem::path& output, bool probe_locks = true);

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
  std::vector<std::string> overrides;  // --set KEY=VALUE
  // A rank other than 0 of a run over MPI ranks: finds the checkpoint as rank 0 does, without
  // probing the staging folders' locks (rank 0 probes them at the same moment) and says nothing.
  bool follower = false;
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
