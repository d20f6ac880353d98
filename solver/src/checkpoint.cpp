// Finding the checkpoint a killed run continues from, and what it must match (checkpoint.hpp).
#include "tactus/solver/checkpoint.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

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
  std::string joined;  // one "KEY=VALUE" per line (a value holds no newline: tactus-solve refuses one)
  for (const std::string& o : overrides) joined += o + "\n";
  a.io("run.overrides", joined);
  overrides.clear();
  for (std::size_t at = 0, nl; (nl = joined.find('\n', at)) != std::string::npos; at = nl + 1) overrides.push_back(joined.substr(at, nl - at));
}

RunIdentity run_identity(const Scenario& sc, const fs::path& mesh_dir) {
  RunIdentity id;
  std::error_code ec;
  id.scenario = fs::absolute(sc.file, ec).lexically_normal().string();
  id.meshes = mesh_dir.empty() ? "" : fs::absolute(mesh_dir, ec).lexically_normal().string();
  id.end_time = sc.run.end_time;
  id.inputs_digest = content_digest(scenario_inputs(sc));
  id.version = kVersion;
  id.overrides = sc.overrides;
  return id;
}

namespace {

constexpr const char* kManifestKind = "tactus-solve checkpoint manifest";

std::string part_name(std::size_t step, int part, int parts) {
  char name[64];
  std::snprintf(name, sizeof name, "checkpoint_%012zu.part%dof%d.h5", step, part, parts);
  return name;
}
std::string manifest_name(std::size_t step) {
  char name[48];
  std::snprintf(name, sizeof name, "checkpoint_%012zu.json", step);
  return name;
}

// The listing a manifest gives, checked: its kind, its step, and each part present with its size.
// InputError naming the manifest otherwise.
CheckpointListing read_manifest(const fs::path& file) {
  const std::string where = file.string();
  require_regular_file(file, "a checkpoint manifest (JSON)");
  if (fs::file_size(file) > (1u << 20)) throw InputError(where, "", "a checkpoint manifest (a few hundred bytes)", "over 1 MB");
  std::ifstream in(file);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (!j.is_object() || j.value("kind", "") != kManifestKind) throw InputError(where, "kind", kManifestKind, "another file");
  if (!j.contains("step") || !j["step"].is_number_unsigned() || !j.contains("time") || !j["time"].is_number() || !j.contains("parts") ||
      !j["parts"].is_array() || j["parts"].empty() || j["parts"].size() > 65536)
    throw InputError(where, "", "step, time and a list of parts", "a manifest without them");
  CheckpointListing c;
  c.manifest = file;
  c.step = j["step"].get<std::size_t>();
  c.time = j["time"].get<double>();
  const auto parts = static_cast<int>(j["parts"].size());
  for (int k = 0; k < parts; ++k) {
    const nlohmann::json& p = j["parts"][static_cast<std::size_t>(k)];
    const std::string expected = part_name(c.step, k, parts);
    if (!p.is_object() || p.value("file", "") != expected || !p.contains("bytes") || !p["bytes"].is_number_unsigned())
      throw InputError(where, "parts[" + std::to_string(k) + "]", "the file " + expected + " and its size", "another entry");
    const fs::path part = file.parent_path() / expected;
    std::error_code ec;
    const auto bytes = fs::file_size(part, ec);
    if (ec || bytes != p["bytes"].get<std::uintmax_t>())
      throw InputError(where, "parts[" + std::to_string(k) + "]", expected + " of " + std::to_string(p["bytes"].get<std::uintmax_t>()) + " bytes",
                       ec ? "missing" : std::to_string(bytes) + " bytes");
    c.parts.push_back(part);
  }
  return c;
}

}  // namespace

CheckpointStore::CheckpointStore(fs::path folder, int part, int parts) : folder_(std::move(folder)), part_(part), parts_(parts) {}

fs::path CheckpointStore::write(std::size_t step, double time, const StateArrays& part, const std::function<void(const char*)>& phase,
                                std::size_t keep, const std::function<void()>& all_parts_written) const {
  fs::create_directories(folder_);
  const fs::path file = folder_ / part_name(step, part_, parts_);
  write_state_file(file, part, phase);
  const fs::path manifest = folder_ / manifest_name(step);
  if (part_ != 0) return manifest;  // (with several parts, part 0 writes the manifest once all are down)
  if (all_parts_written) all_parts_written();
  if (phase) phase("manifest");
  nlohmann::json parts = nlohmann::json::array();
  for (int k = 0; k < parts_; ++k) {
    const std::string name = part_name(step, k, parts_);
    std::error_code ec;
    const auto bytes = fs::file_size(folder_ / name, ec);
    if (ec)  // another machine's rank wrote its part into a folder of its own
      throw WriteError((folder_ / name).string(), "part " + std::to_string(k) +
                                                      " of the checkpoint is not there: every rank writes its part into this "
                                                      "folder, so on several machines the output folder must be on a file system they share");
    parts.push_back({{"file", name}, {"bytes", bytes}});
  }
  const nlohmann::json j{{"kind", kManifestKind}, {"step", step}, {"time", time}, {"parts", parts}};
  const fs::path temporary = manifest.string() + ".partial-" + unique_suffix();
  write_file(temporary, j.dump(1) + "\n");
  fs::rename(temporary, manifest);
  sync_directory(folder_);
  // The newest `keep` complete checkpoints stay; older manifests go first, then every part no
  // kept manifest lists (an older checkpoint's, or one a killed run left without its manifest).
  const std::vector<CheckpointListing> complete = list_checkpoints(folder_);
  std::vector<fs::path> kept;
  for (std::size_t i = 0; i < complete.size(); ++i) {
    if (i < keep) {
      kept.insert(kept.end(), complete[i].parts.begin(), complete[i].parts.end());
      kept.push_back(complete[i].manifest);
    } else {
      fs::remove(complete[i].manifest);
    }
  }
  for (const auto& e : fs::directory_iterator(folder_)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("checkpoint_", 0) == 0 && name.find(".partial-") == std::string::npos &&
        std::find(kept.begin(), kept.end(), e.path()) == kept.end())
      fs::remove(e.path());
  }
  return manifest;
}

const std::vector<std::string> kCheckpointNodeArrays = {"integrator.u",
                                                        "integrator.v_half",
                                                        "integrator.v_prev_half",
                                                        "integrator.force",
                                                        "integrator.inverse_mass",
                                                        "integrator.nodal_mass",
                                                        "integrator.contact_inverse_mass",
                                                        "integrator.prescribed_velocity",
                                                        "integrator.pressure_force"};

namespace {
// Per part: the nodes it holds, and per array of kCheckpointNodeArrays its values per node (-1:
// the run has no such array).
constexpr const char* kPartNodes = "part.nodes";
constexpr const char* kPartWidths = "part.widths";
}  // namespace

StateArrays checkpoint_part(const StateArrays& whole, const std::vector<std::uint32_t>& nodes, std::size_t num_nodes, bool first) {
  StateArrays part;
  if (first) part = whole;
  part.kind = whole.kind;
  part.integers[kPartNodes].assign(nodes.begin(), nodes.end());
  std::vector<std::int64_t>& widths = part.integers[kPartWidths];
  for (const std::string& name : kCheckpointNodeArrays) {
    const auto it = whole.reals.find(name);
    if (it == whole.reals.end()) {
      widths.push_back(-1);
      continue;
    }
    const std::size_t width = num_nodes ? it->second.size() / num_nodes : 0;  // 3 per node, 1, or 0 (an array the run leaves empty)
    widths.push_back(static_cast<std::int64_t>(width));
    std::vector<double>& mine = part.reals[name];
    mine.clear();
    for (std::uint32_t n : nodes)
      mine.insert(mine.end(), it->second.begin() + static_cast<std::ptrdiff_t>(width * n),
                  it->second.begin() + static_cast<std::ptrdiff_t>(width * (n + 1)));
  }
  return part;
}

StateArrays merge_checkpoint_parts(std::vector<StateArrays> parts, const std::vector<fs::path>& files) {
  const auto refuse = [&](std::size_t k, const std::string& what, const std::string& expected, const std::string& found) {
    throw InputError(files.at(k).string(), what, expected, found);
  };
  const auto integers = [&](std::size_t k, const char* name) -> const std::vector<std::int64_t>& {
    const auto it = parts[k].integers.find(name);
    if (it == parts[k].integers.end()) refuse(k, name, "a part of a checkpoint written over MPI ranks", "no " + std::string(name));
    return it->second;
  };
  const std::vector<std::int64_t> widths = integers(0, kPartWidths);
  if (widths.size() != kCheckpointNodeArrays.size())
    refuse(0, kPartWidths, std::to_string(kCheckpointNodeArrays.size()) + " arrays", std::to_string(widths.size()));
  std::size_t num_nodes = 0;
  for (std::size_t k = 0; k < parts.size(); ++k) num_nodes += integers(k, kPartNodes).size();
  std::vector<char> seen(num_nodes, 0);
  std::vector<std::vector<double>> full(widths.size());
  for (std::size_t j = 0; j < widths.size(); ++j) full[j].resize(static_cast<std::size_t>(std::max<std::int64_t>(widths[j], 0)) * num_nodes);
  for (std::size_t k = 0; k < parts.size(); ++k) {
    if (integers(k, kPartWidths) != widths) refuse(k, kPartWidths, "part 0's", "other values per node");
    const std::vector<std::int64_t>& nodes = integers(k, kPartNodes);
    for (std::int64_t n : nodes) {
      if (n < 0 || static_cast<std::size_t>(n) >= num_nodes || seen[static_cast<std::size_t>(n)])
        refuse(k, kPartNodes, "nodes 0 to " + std::to_string(num_nodes - 1) + " over the parts, each in one", "node " + std::to_string(n));
      seen[static_cast<std::size_t>(n)] = 1;
    }
    for (std::size_t j = 0; j < widths.size(); ++j) {
      if (widths[j] < 0) continue;
      const auto width = static_cast<std::size_t>(widths[j]);
      const auto it = parts[k].reals.find(kCheckpointNodeArrays[j]);
      if (it == parts[k].reals.end() || it->second.size() != width * nodes.size())
        refuse(k, kCheckpointNodeArrays[j], std::to_string(width * nodes.size()) + " values (" + std::to_string(width) + " per node)",
               it == parts[k].reals.end() ? "none" : std::to_string(it->second.size()));
      for (std::size_t i = 0; i < nodes.size(); ++i)
        std::copy_n(it->second.begin() + static_cast<std::ptrdiff_t>(width * i), width,
                    full[j].begin() + static_cast<std::ptrdiff_t>(width * static_cast<std::size_t>(nodes[i])));
    }
  }
  StateArrays whole = std::move(parts[0]);
  for (std::size_t j = 0; j < widths.size(); ++j)
    if (widths[j] >= 0) whole.reals[kCheckpointNodeArrays[j]] = std::move(full[j]);
  whole.integers.erase(kPartNodes), whole.integers.erase(kPartWidths);
  return whole;
}

std::vector<CheckpointListing> list_checkpoints(const fs::path& folder) {
  std::vector<CheckpointListing> found;
  std::error_code ec;
  for (auto it = fs::directory_iterator(folder, ec); !ec && it != fs::directory_iterator(); it.increment(ec)) {
    const std::string name = it->path().filename().string();
    std::size_t step = 0;
    char tail[8] = {};
    // checkpoint_<step>.json exactly: a half-written one still has its .partial-<pid> suffix.
    if (std::sscanf(name.c_str(), "checkpoint_%zu.%7s", &step, tail) != 2 || std::string(tail) != "json") continue;
    try {
      found.push_back(read_manifest(it->path()));
    } catch (const InputError& e) {
      log::warn(std::string("checkpoint not usable: ") + e.what());
    }
  }
  std::sort(found.begin(), found.end(), [](const CheckpointListing& a, const CheckpointListing& b) { return a.step > b.step; });
  return found;
}

std::optional<RestartPoint> find_restart_point(const fs::path& output, bool probe_locks) {
  // Every complete checkpoint of every killed run writing `output`, newest (highest step) first.
  std::vector<CheckpointListing> found;
  for (const fs::path& staging : resumable_staging(output, "tactus-solve", probe_locks)) {
    std::vector<CheckpointListing> here = list_checkpoints(staging / kResumableDir);
    found.insert(found.end(), here.begin(), here.end());
  }
  std::stable_sort(found.begin(), found.end(), [](const CheckpointListing& a, const CheckpointListing& b) { return a.step > b.step; });
  for (const CheckpointListing& c : found) {
    try {
      RestartPoint p;
      p.file = c.parts.front();
      p.staging = c.manifest.parent_path().parent_path();
      std::vector<StateArrays> parts;
      for (const fs::path& part : c.parts) parts.push_back(read_state_file(part, kCheckpointKind));
      // A run over MPI ranks wrote one part per rank: put together, whatever the ranks now.
      StateArchive a(parts.size() == 1 ? std::move(parts[0]) : merge_checkpoint_parts(std::move(parts), c.parts), p.file.string());
      p.identity.io(a);
      a.io("integrator.step", p.step);
      a.io("integrator.time", p.time);
      if (p.step != c.step)
        throw InputError(p.file.string(), "integrator.step", "step " + std::to_string(c.step) + " (its manifest's)", std::to_string(p.step));
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
  if (p.identity.overrides != id.overrides) {
    auto list = [](const std::vector<std::string>& v) {
      std::string s;
      for (const std::string& o : v) s += (s.empty() ? "--set " : " --set ") + o;
      return s.empty() ? std::string("no --set") : s;
    };
    refuse("run.overrides", list(p.identity.overrides), list(id.overrides));
  }
  if (p.identity.inputs_digest != id.inputs_digest)
    refuse("run.inputs_digest", "the scenario, meshes and fibre files as they were", "one of them has changed");
}

PreparedRun prepare_run(SolveRequest q) {
  PreparedRun p;
  if (!q.restart.empty()) {
    if (!q.scenario.empty() || !q.meshes.empty() || q.end_time || !q.output.empty() || !q.overrides.empty())
      throw InputError("command line", "--restart", "the output folder alone (the scenario, --meshes, --end-time, --set and -o are the checkpoint's)",
                       "more arguments");
    p.from = find_restart_point(q.restart, !q.follower);
    if (!p.from)
      throw InputError(q.restart.string(), "--restart", "a killed tactus-solve run writing this folder, with a checkpoint (run.checkpoint_interval)",
                       "none: nothing to continue");
    q.scenario = p.from->identity.scenario, q.meshes = p.from->identity.meshes, q.output = q.restart;
    q.end_time = p.from->identity.end_time;
    q.overrides = p.from->identity.overrides;
  }
  if (q.scenario.empty()) throw InputError("command line", "scenario", "a scenario.toml", "none");
  p.scenario_file = q.scenario;
  for (const std::string& o : q.overrides)
    if (o.find('\n') != std::string::npos) throw InputError("command line", "--set", "KEY=VALUE on one line", "a newline in \"" + o + "\"");
  p.scenario = read_scenario(q.scenario, q.meshes, q.overrides);
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
    p.from = find_restart_point(p.output, !q.follower);
    if (p.from) {
      try {
        check_restart_identity(*p.from, p.identity);
      } catch (const InputError& e) {
        log::warn(std::string("not continuing the killed run: ") + e.what() + "; starting from t = 0");
        p.from.reset();
      }
    }
  }
  if (!p.from && !q.resume && !q.follower)
    for (const auto& killed : resumable_staging(p.output, "tactus-solve"))
      log::warn("a killed run writing " + p.output.string() + " can still be continued (tactus-solve --restart " + p.output.string() +
                "); its folder " + killed.string() + " is kept: delete it to drop it");
  return p;
}

}  // namespace tactus::solver
