// Finding the checkpoint a killed run continues from, and what it must match (checkpoint.hpp).
#include "tactus/solver/checkpoint.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/output.hpp"
#include "tactus/core/version.hpp"
#include "tactus/solver/run.hpp"

namespace fs = std::filesystem;

namespace tactus::solver {

void RunIdentity::io(StateArchive& a) {
  a.io("run.scenario", scenario);
  a.io("run.meshes", meshes);
  a.io("run.end_time", end_time);
  a.io("run.inputs_digest", inputs_digest);
  a.io("run.version", version);
}

RunIdentity run_identity(const Scenario& sc, const fs::path& mesh_dir) {
  RunIdentity id;
  std::error_code ec;
  id.scenario = fs::absolute(sc.file, ec).lexically_normal().string();
  id.meshes = mesh_dir.empty() ? "" : fs::absolute(mesh_dir, ec).lexically_normal().string();
  id.end_time = sc.run.end_time;
  id.inputs_digest = content_digest(scenario_inputs(sc));
  id.version = kVersion;
  return id;
}

std::optional<RestartPoint> find_restart_point(const fs::path& output) {
  // Every checkpoint of every killed run writing `output`, newest (highest step) first.
  std::vector<std::pair<std::size_t, fs::path>> found;
  for (const fs::path& staging : resumable_staging(output, "tactus-solve")) {
    std::error_code ec;
    for (auto it = fs::directory_iterator(staging / kResumableDir, ec); !ec && it != fs::directory_iterator(); it.increment(ec)) {
      const std::string name = it->path().filename().string();
      std::size_t step = 0;
      char tail = 0;
      // checkpoint_<step>.h5 exactly: a half-written one still has its .partial-<pid> suffix.
      if (std::sscanf(name.c_str(), "checkpoint_%zu.h%c", &step, &tail) == 2 && tail == '5' && name.size() > 3 &&
          name.compare(name.size() - 3, 3, ".h5") == 0)
        found.emplace_back(step, it->path());
    }
  }
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (const auto& [step, file] : found) {
    try {
      RestartPoint p;
      p.file = file;
      p.staging = file.parent_path().parent_path();
      StateArchive a(read_state_file(file, kCheckpointKind), file.string());
      p.identity.io(a);
      a.io("integrator.step", p.step);
      a.io("integrator.time", p.time);
      p.state = std::move(a.arrays());
      return p;
    } catch (const InputError& e) {
      log::warn(std::string("checkpoint not usable, taking the one before it: ") + e.what());
    }
  }
  return std::nullopt;
}

void check_restart_identity(const RestartPoint& p, const RunIdentity& id) {
  auto refuse = [&](const std::string& what, const std::string& then, const std::string& now) {
    throw InputError(p.file.string(), what, then + " (as when the run was started)", now + "; start the run again without --restart");
  };
  if (p.identity.scenario != id.scenario) refuse("run.scenario", p.identity.scenario, id.scenario);
  if (p.identity.meshes != id.meshes) refuse("run.meshes", "--meshes '" + p.identity.meshes + "'", "'" + id.meshes + "'");
  if (p.identity.end_time != id.end_time) {
    std::ostringstream a, b;
    a << "end time " << p.identity.end_time << " s";
    b << id.end_time << " s";
    refuse("run.end_time", a.str(), b.str());
  }
  if (p.identity.version != id.version) refuse("run.version", "tactus " + p.identity.version, "tactus " + id.version);
  if (p.identity.inputs_digest != id.inputs_digest)
    refuse("run.inputs_digest", "the scenario, meshes and fibre files as they were", "one of them has changed");
}

PreparedRun prepare_run(SolveRequest q) {
  PreparedRun p;
  if (!q.restart.empty()) {
    if (!q.scenario.empty() || !q.meshes.empty() || q.end_time || !q.output.empty())
      throw InputError("command line", "--restart", "the output folder alone (the scenario, --meshes, --end-time and -o are the checkpoint's)",
                       "more arguments");
    p.from = find_restart_point(q.restart);
    if (!p.from)
      throw InputError(q.restart.string(), "--restart", "a killed tactus-solve run writing this folder, with a checkpoint (run.checkpoint_interval)",
                       "none: nothing to continue");
    q.scenario = p.from->identity.scenario, q.meshes = p.from->identity.meshes, q.output = q.restart;
    q.end_time = p.from->identity.end_time;
  }
  if (q.scenario.empty()) throw InputError("command line", "scenario", "a scenario.toml", "none");
  p.scenario_file = q.scenario;
  p.scenario = read_scenario(q.scenario, q.meshes);
  // --end-time (or the end time a restarted run was started with): later output times are dropped.
  if (q.end_time && (!(*q.end_time > 0) || !std::isfinite(*q.end_time)))
    throw InputError("command line", "--end-time", "a time > 0 in s", std::to_string(*q.end_time));
  if (q.end_time && *q.end_time != p.scenario.run.end_time) {
    const double end = *q.end_time;
    p.scenario.run.end_time = end;
    std::erase_if(p.scenario.run.output_times, [&](double t) { return t > end * (1 + 1e-12); });
  }
  p.output = q.output.empty() ? q.scenario.parent_path() / "results" : q.output;
  p.identity = run_identity(p.scenario, q.meshes);
  if (p.from) check_restart_identity(*p.from, p.identity);
  if (q.resume && !p.from) {
    p.from = find_restart_point(p.output);
    if (p.from) {
      try {
        check_restart_identity(*p.from, p.identity);
      } catch (const InputError& e) {
        log::warn(std::string("not continuing the killed run: ") + e.what() + "; starting from t = 0");
        p.from.reset();
      }
    }
  }
  if (!p.from && !q.resume)
    for (const auto& killed : resumable_staging(p.output, "tactus-solve"))
      log::warn("a killed run writing " + p.output.string() + " can still be continued (tactus-solve --restart " + p.output.string() +
                "); its folder " + killed.string() + " is kept: delete it to drop it");
  return p;
}

}  // namespace tactus::solver
