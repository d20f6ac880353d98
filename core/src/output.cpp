// Output folders and files that never delete what tactus did not write (see output.hpp).
#include "tactus/core/output.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/core/interrupt.hpp"
#include "tactus/core/version.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace tactus {

namespace {

// ---------------------------------------------------------------------------------------------
// Which process wrote a staging folder, and whether it still runs (a pid alone may be reused).
struct ProcessId {
  long pid = 0;
  unsigned long long start = 0;  // /proc/<pid>/stat field 22: start time in clock ticks since boot
  std::string boot;              // /proc/sys/kernel/random/boot_id
};

std::string read_small_file(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

unsigned long long process_start(long pid) {
  const std::string stat = read_small_file("/proc/" + std::to_string(pid) + "/stat");
  // The command name (field 2) is in parentheses and may contain spaces: count from the last ')'.
  const auto close = stat.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream rest(stat.substr(close + 2));
  std::string field;
  for (int i = 3; i <= 22 && rest >> field; ++i)
    if (i == 22) return std::strtoull(field.c_str(), nullptr, 10);
  return 0;
}

ProcessId this_process() {
  ProcessId id;
  id.pid = static_cast<long>(getpid());
  id.start = process_start(id.pid);
  id.boot = read_small_file("/proc/sys/kernel/random/boot_id");
  while (!id.boot.empty() && (id.boot.back() == '\n' || id.boot.back() == ' ')) id.boot.pop_back();
  return id;
}

bool still_running(const ProcessId& id) {
  const ProcessId me = this_process();
  if (id.boot != me.boot) return false;  // written before the last reboot
  if (id.pid <= 0) return false;
  return process_start(id.pid) == id.start && id.start != 0;
}

// ---------------------------------------------------------------------------------------------
// Markers.
std::int64_t mtime_ns(const fs::path& p) {
  std::error_code ec;
  const auto t = fs::last_write_time(p, ec);
  return ec ? 0 : static_cast<std::int64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count());
}

json file_entry(const fs::path& p) {
  std::error_code ec;
  return {{"size", static_cast<std::uintmax_t>(fs::file_size(p, ec))}, {"mtime_ns", mtime_ns(p)}};
}

// A marker's JSON, or null when it is missing or not ours.
json read_marker(const fs::path& p) {
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) return nullptr;
  std::ifstream in(p);
  json j = json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return nullptr;
  return j;
}

void write_json_atomically(const fs::path& p, const json& j) {
  const fs::path tmp = p.string() + ".tmp-" + std::to_string(getpid());
  {
    std::ofstream out(tmp);
    out << j.dump(1) << '\n';
    if (!out) throw WriteError(p.string(), "the file system refused the write");
  }
  std::error_code ec;
  fs::rename(tmp, p, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw WriteError(p.string(), ec.message());
  }
}

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

json staging_marker(const std::string& tool) {
  const ProcessId me = this_process();
  return {{"tool", tool}, {"version", kVersion}, {"state", "writing"}, {"pid", me.pid}, {"process_start", me.start}, {"boot_id", me.boot}};
}

// ---------------------------------------------------------------------------------------------
fs::path canonical_path(const fs::path& p) {
  std::error_code ec;
  fs::path abs = fs::absolute(p, ec);
  if (ec) abs = p;
  fs::path c = fs::weakly_canonical(abs, ec);
  return ec ? abs.lexically_normal() : c;
}

bool is_same_or_ancestor(const fs::path& ancestor, const fs::path& p) {
  auto a = ancestor.begin(), b = p.begin();
  for (; a != ancestor.end(); ++a, ++b) {
    if (a->empty()) continue;  // trailing separator
    if (b == p.end() || *a != *b) return false;
  }
  return true;
}

// The place rules: not the current folder, not the root, not an input nor a folder containing one.
void check_place(const fs::path& final, const OutputRules& rules, const std::string& kind) {
  if (final.empty()) throw InputError("command line", "-o/--output", "an output " + kind, "an empty path");
  const fs::path abs = canonical_path(final);
  std::error_code ec;
  if (abs == canonical_path(fs::current_path(ec)))
    throw WriteError(final.string(), "it is the current folder; tactus writes its " + kind +
                                         " into a new folder (e.g. -o results) and never replaces the folder you work in");
  if (abs == abs.root_path()) throw WriteError(final.string(), "it is the root of the file system");
  for (const auto& input : rules.inputs) {
    if (input.empty()) continue;
    const fs::path in = canonical_path(input);
    if (in == abs) throw WriteError(final.string(), "it is an input of this run (" + input.string() + "); choose another output");
    if (is_same_or_ancestor(abs, in))
      throw WriteError(final.string(), "it contains an input of this run (" + input.string() + "); tactus would replace it: choose a new folder");
  }
}

// Creates the parent folders of a final path, as a WriteError when impossible.
void make_parent(const fs::path& final) {
  const fs::path parent = canonical_path(final).parent_path();
  std::error_code ec;
  if (fs::is_directory(parent, ec)) return;
  fs::create_directories(parent, ec);
  if (ec || !fs::is_directory(parent)) throw WriteError(parent.string(), "cannot create the folder (" + ec.message() + ")");
}

// Files under `dir` (relative paths) with their entries; anything that is neither a regular file
// nor a folder is reported through `odd`.
json snapshot(const fs::path& dir, std::string* odd = nullptr) {
  json files = json::object();
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    const fs::path rel = it->path().lexically_relative(dir);
    if (rel == kFolderMarker || rel == kFilesMarker) continue;  // tactus's own records
    if (it->is_symlink()) {
      if (odd && odd->empty()) *odd = rel.string() + " (a link)";
      it.disable_recursion_pending();
      continue;
    }
    if (it->is_directory()) continue;
    if (!it->is_regular_file()) {
      if (odd && odd->empty()) *odd = rel.string();
      continue;
    }
    files[rel.generic_string()] = file_entry(it->path());
  }
  return files;
}

std::string first_entry(const fs::path& dir) {
  std::error_code ec;
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir, ec)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names.empty() ? "" : names.front();
}

// Throws unless `final` (a folder) may be replaced by an output of rules.tool.
void check_folder_replaceable(const fs::path& final, const OutputRules& rules) {
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(final, ec))) return;
  if (fs::is_symlink(fs::symlink_status(final, ec))) throw WriteError(final.string(), "it is a link; give the folder itself, or a new folder");
  if (!fs::is_directory(final, ec)) throw WriteError(final.string(), "it is a file, not a folder; choose a new folder");
  if (fs::is_empty(final, ec)) return;
  const json marker = read_marker(final / kFolderMarker);
  if (marker.is_null() || !marker.contains("files") || !marker["files"].is_object() || marker.value("state", "") != "complete") {
    std::size_t n = 0;
    for (auto it = fs::directory_iterator(final, ec); !ec && it != fs::directory_iterator(); it.increment(ec)) ++n;
    throw WriteError(final.string(), "it is a folder tactus did not write (" + std::to_string(n) + " entries, e.g. '" + first_entry(final) +
                                         "'); tactus never replaces it: choose a new or empty folder");
  }
  const std::string writer = marker.value("tool", "");
  if (writer != rules.tool && !rules.force)
    throw WriteError(final.string(),
                     "it holds the output of " + writer + ", not of " + rules.tool + "; give --force to replace it, or choose another folder");
  std::string odd;
  const json now = snapshot(final, &odd);
  if (!odd.empty()) throw WriteError(final.string(), "'" + odd + "' in it was not written by tactus; move it away first");
  const json& listed = marker["files"];
  for (const auto& [name, entry] : now.items()) {
    if (!listed.contains(name))
      throw WriteError(final.string(), "'" + name + "' in it was not written by tactus; move it away, or choose another folder");
    if (listed[name] != entry)
      throw WriteError(final.string(), "'" + name + "' in it changed since tactus wrote it; move it away, or choose another folder");
  }
}

// Removes what the marker of a replaced output lists, then its empty folders. Anything else stays.
void remove_listed(const fs::path& dir, const json& files) {
  std::error_code ec;
  for (const auto& [name, entry] : files.items()) fs::remove(dir / name, ec);
  fs::remove(dir / kFolderMarker, ec);
  fs::remove(dir / kFilesMarker, ec);  // a list of files tactus wrote here later (OutputFiles), all of them listed above
  std::vector<fs::path> dirs;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator(); it.increment(ec))
    if (it->is_directory() && !it->is_symlink()) dirs.push_back(it->path());
  std::sort(dirs.rbegin(), dirs.rend());         // deepest first
  for (const auto& d : dirs) fs::remove(d, ec);  // only removes empty folders
  fs::remove(dir, ec);
}

// Staging folders `<name>.partial-*` of `tool` whose process is gone; `resumable`: only those
// holding a kResumableDir (a killed run that can be continued), else only those without.
std::vector<fs::path> dead_staging(const fs::path& final, const std::string& tool, bool resumable) {
  std::vector<fs::path> found;
  const fs::path parent = canonical_path(final).parent_path();
  const std::string prefix = final.filename().string() + ".partial-";
  std::error_code ec;
  for (auto it = fs::directory_iterator(parent, ec); !ec && it != fs::directory_iterator(); it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(prefix, 0) != 0 || !it->is_directory()) continue;
    const json m = read_marker(it->path() / kFolderMarker);
    if (m.is_null() || m.value("tool", "") != tool || m.value("state", "") != "writing") continue;
    ProcessId id;
    id.pid = m.value("pid", 0L);
    id.start = m.value("process_start", 0ULL);
    id.boot = m.value("boot_id", "");
    if (still_running(id)) continue;
    std::error_code exists;
    if (fs::is_directory(it->path() / kResumableDir, exists) == resumable) found.push_back(it->path());
  }
  std::sort(found.begin(), found.end());
  return found;
}

// Staging folders of `tool` whose process is gone, except those a killed run can be continued from.
void remove_stale_staging(const fs::path& final, const std::string& tool) {
  for (const fs::path& p : dead_staging(final, tool, false)) {
    std::error_code rm;
    fs::remove_all(p, rm);
  }
}

// Creates a staging folder with its "writing" marker: proves the place is writable.
fs::path create_staging(const fs::path& final, const std::string& tool) {
  const fs::path staging = canonical_path(final).parent_path() / (final.filename().string() + ".partial-" + std::to_string(getpid()));
  std::error_code ec;
  fs::remove_all(staging, ec);  // our own pid: a leftover of this very process
  fs::create_directory(staging, ec);
  if (ec) throw WriteError(staging.parent_path().string(), "cannot create a folder there (" + ec.message() + ")");
  register_staging_path(staging);
  try {
    write_json_atomically(staging / kFolderMarker, staging_marker(tool));
  } catch (...) {
    fs::remove_all(staging, ec);
    unregister_staging_path(staging);
    throw;
  }
  return staging;
}

void check_space(const fs::path& where, std::uintmax_t bytes, const std::string& what, const fs::path& final) {
  std::error_code ec;
  const fs::space_info s = fs::space(where, ec);
  if (ec) return;
  if (s.available < bytes + bytes / 10)
    throw WriteError(final.string(), what + " needs about " + human_bytes(bytes) + " but only " + human_bytes(s.available) +
                                         " is free there; free some space or write elsewhere");
}

void discard_staging(fs::path& staging) {
  if (staging.empty()) return;
  std::error_code ec;
  fs::remove_all(staging, ec);
  unregister_staging_path(staging);
}

// The files manifest of a directory (files tactus wrote there). A directory that is itself a
// complete tactus output folder (an earlier version wrote `tactus-mesh -o mesh/` where the
// pipeline now writes `-o mesh/mesh.msh`) lends its marker's top-level files, so a user's
// previous results are recognised as tactus's after an upgrade.
json read_files_manifest(const fs::path& dir) {
  const fs::path p = dir / kFilesMarker;
  std::error_code ec;
  json m = json{{"files", json::object()}};
  if (fs::exists(p, ec)) {
    m = read_marker(p);
    if (m.is_null() || !m.contains("files") || !m["files"].is_object())
      throw WriteError(p.string(), "it is not a tactus output list (unreadable); move it away");
  }
  const json folder = fs::exists(dir / kFolderMarker, ec) ? read_marker(dir / kFolderMarker) : json();
  if (!folder.is_null() && folder.value("state", "") == "complete" && folder.contains("files") && folder["files"].is_object())
    for (const auto& [name, entry] : folder["files"].items())
      if (name.find('/') == std::string::npos && !m["files"].contains(name) && entry.is_object()) {
        json e = entry;
        e["tool"] = folder.value("tool", "");
        m["files"][name] = e;
      }
  return m;
}

// After files were replaced in a directory that is also a tactus output folder, that folder's
// marker lists their new sizes and times, so it stays a valid record of what tactus wrote.
void update_folder_marker(const fs::path& dir, const std::vector<fs::path>& replaced) {
  std::error_code ec;
  if (!fs::exists(dir / kFolderMarker, ec)) return;
  json folder = read_marker(dir / kFolderMarker);
  if (folder.is_null() || !folder.contains("files") || !folder["files"].is_object()) return;
  for (const auto& f : replaced) folder["files"][f.filename().string()] = file_entry(f);
  write_json_atomically(dir / kFolderMarker, folder);
}

void check_file_replaceable(const fs::path& final, const OutputRules& rules, const json& manifest) {
  std::error_code ec;
  const auto st = fs::symlink_status(final, ec);
  if (!fs::exists(st)) return;
  if (!fs::is_regular_file(st)) throw WriteError(final.string(), "something other than a file is there; choose another name");
  const std::string name = final.filename().string();
  const json& files = manifest["files"];
  if (!files.contains(name)) throw WriteError(final.string(), "the file exists and tactus did not write it; choose another name, or move it away");
  const json& entry = files[name];
  if (entry.value("size", std::uintmax_t{0}) != fs::file_size(final, ec) || entry.value("mtime_ns", std::int64_t{0}) != mtime_ns(final))
    throw WriteError(final.string(), "the file changed since tactus wrote it; choose another name, or move it away");
  const std::string writer = entry.value("tool", "");
  if (writer != rules.tool && !rules.force)
    throw WriteError(final.string(), "it was written by " + writer + ", not by " + rules.tool + "; give --force to replace it");
}

}  // namespace

std::string human_bytes(std::uintmax_t bytes) {
  const char* units[] = {"B", "kB", "MB", "GB", "TB"};
  double v = static_cast<double>(bytes);
  int u = 0;
  while (v >= 1000 && u < 4) v /= 1000, ++u;
  char buf[32];
  std::snprintf(buf, sizeof buf, u == 0 ? "%.0f %s" : "%.1f %s", v, units[u]);
  return buf;
}

// ---------------------------------------------------------------------------------------------
OutputFolder::OutputFolder(fs::path folder, OutputRules rules, const fs::path& resume) : final_(std::move(folder)), rules_(std::move(rules)) {
  check_place(final_, rules_, "output folder");
  check_folder_replaceable(final_, rules_);
  make_parent(final_);
  remove_stale_staging(final_, rules_.tool);
  if (resume.empty()) {
    staging_ = create_staging(final_, rules_.tool);
    return;
  }
  // The killed run's staging folder becomes this process's: renamed to our pid, marked as ours.
  const std::vector<fs::path> dead = dead_staging(final_, rules_.tool, true);
  if (std::find(dead.begin(), dead.end(), canonical_path(resume)) == dead.end())
    throw InputError(resume.string(), "", "the staging folder of a killed " + rules_.tool + " run writing " + final_.string(),
                     "not one (its process still runs, or it belongs elsewhere)");
  staging_ = canonical_path(final_).parent_path() / (final_.filename().string() + ".partial-" + std::to_string(getpid()));
  std::error_code ec;
  fs::rename(resume, staging_, ec);
  if (ec) throw WriteError(resume.string(), "cannot take over the interrupted run's folder (" + ec.message() + ")");
  register_staging_path(staging_);
  write_json_atomically(staging_ / kFolderMarker, staging_marker(rules_.tool));
}

OutputFolder::~OutputFolder() {
  if (!committed_ && !kept_) discard_staging(staging_);
}

void OutputFolder::keep_for_resume() {
  kept_ = true;
  unregister_staging_path(staging_);
}

std::vector<fs::path> resumable_staging(const fs::path& folder, const std::string& tool) { return dead_staging(folder, tool, true); }

void OutputFolder::require_space(std::uintmax_t bytes, const std::string& what) const { check_space(staging_, bytes, what, final_); }

void OutputFolder::commit() {
  check_folder_replaceable(final_, rules_);
  json marker = {{"tool", rules_.tool}, {"version", kVersion}, {"state", "complete"}, {"written_utc", utc_now()}};
  marker["files"] = snapshot(staging_);
  write_json_atomically(staging_ / kFolderMarker, marker);
  std::error_code ec;
  const bool replace = fs::exists(final_, ec) && !fs::is_empty(final_, ec);
  const fs::path trash = final_.string() + ".replaced-" + std::to_string(getpid());
  json old_files = json::object();
  if (replace) {
    old_files = read_marker(final_ / kFolderMarker)["files"];
    fs::rename(final_, trash, ec);
    if (ec) throw WriteError(final_.string(), "cannot move the previous output aside (" + ec.message() + ")");
  }
  fs::rename(staging_, final_, ec);
  if (ec) {
    std::error_code back;
    if (replace) fs::rename(trash, final_, back);
    throw WriteError(final_.string(), "cannot move the output into place (" + ec.message() + ")");
  }
  unregister_staging_path(staging_);
  committed_ = true;
  if (replace) remove_listed(trash, old_files);
}

// ---------------------------------------------------------------------------------------------
OutputFiles::OutputFiles(std::vector<fs::path> files, OutputRules rules) : finals_(std::move(files)), rules_(std::move(rules)) {
  if (finals_.empty()) throw InputError("command line", "-o/--output", "an output file");
  dir_ = canonical_path(finals_.front()).parent_path();
  for (const auto& f : finals_) {
    check_place(f, rules_, "output file");
    if (canonical_path(f).parent_path() != dir_) throw InputError("command line", "-o/--output", "output files in one folder", f.string());
    std::error_code ec;
    if (fs::is_directory(f, ec)) throw WriteError(f.string(), "it is a folder; give a file name (or a folder output without the extension)");
  }
  make_parent(finals_.front());
  const json manifest = read_files_manifest(dir_);
  for (const auto& f : finals_) check_file_replaceable(f, rules_, manifest);
  remove_stale_staging(finals_.front(), rules_.tool);
  staging_ = create_staging(finals_.front(), rules_.tool);
}

OutputFiles::~OutputFiles() {
  if (!committed_) discard_staging(staging_);
}

fs::path OutputFiles::staged(std::size_t i) const { return staging_ / finals_.at(i).filename(); }

void OutputFiles::require_space(std::uintmax_t bytes, const std::string& what) const { check_space(staging_, bytes, what, finals_.front()); }

void OutputFiles::commit() {
  json manifest = read_files_manifest(dir_);
  for (const auto& f : finals_) check_file_replaceable(f, rules_, manifest);
  for (std::size_t i = 0; i < finals_.size(); ++i) {
    std::error_code ec;
    if (!fs::exists(staged(i), ec)) throw WriteError(finals_[i].string(), "the tool wrote nothing there (internal error)");
  }
  for (std::size_t i = 0; i < finals_.size(); ++i) {
    std::error_code ec;
    fs::rename(staged(i), finals_[i], ec);
    if (ec) throw WriteError(finals_[i].string(), "cannot move the file into place (" + ec.message() + ")");
    json entry = file_entry(finals_[i]);
    entry["tool"] = rules_.tool;
    manifest["files"][finals_[i].filename().string()] = entry;
  }
  write_json_atomically(dir_ / kFilesMarker, manifest);
  update_folder_marker(dir_, finals_);
  committed_ = true;
  discard_staging(staging_);
}

}  // namespace tactus
