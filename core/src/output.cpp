// Output folders and files that never delete what tactus did not write (see output.hpp).
#include "tactus/core/output.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/interrupt.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/version.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace tactus {

namespace {

// ---------------------------------------------------------------------------------------------
// Locks: an exclusive flock on `<folder>/.tactus-lock`, held by the process writing the folder
// for as long as it lives (the kernel releases it when the process ends, however it ends).
enum class LockState { taken, held, missing };

LockState try_lock(const fs::path& folder, int& fd) {
  fd = ::open((folder / kLockFile).c_str(), O_RDWR | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return LockState::missing;
  if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return LockState::taken;
  ::close(fd);
  fd = -1;
  return LockState::held;
}

void release(int& fd) {
  if (fd >= 0) ::close(fd);
  fd = -1;
}

// Creates the lock file of a new staging folder and takes it.
int create_lock(const fs::path& folder) {
  const int fd = ::open((folder / kLockFile).c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) throw WriteError(folder.string(), "cannot create its lock file", errno);
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd);
    throw WriteError(folder.string(), "cannot lock it", errno);
  }
  return fd;
}

// The safety tests' way to die like a killed process between the steps of a commit, from the
// environment (never set in normal use): TACTUS_KILL_AT="commit:complete" (the output complete in
// its staging folder, before the swap) or "commit:swapped" (after the swap, before the previous
// output is sorted).
void test_kill_point(const char* phase) {
  static const char* spec = std::getenv("TACTUS_KILL_AT");
  if (spec && std::string(spec) == std::string("commit:") + phase) std::raise(SIGKILL);
}

// ---------------------------------------------------------------------------------------------
// Markers (manifests).
json read_marker(const fs::path& p) {  // null when missing or not ours
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) return nullptr;
  std::ifstream in(p);
  json j = json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return nullptr;
  return j;
}

void write_json_atomically(const fs::path& p, const json& j) {
  const fs::path tmp = p.string() + ".tmp-" + unique_suffix();
  try {
    write_file(tmp, j.dump(1) + '\n');
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
  std::error_code ec;
  fs::rename(tmp, p, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw WriteError(p.string(), "cannot move the manifest into place", ec.value());
  }
}

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

std::int64_t now_ns() { return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count(); }

json staging_marker(const std::string& tool, const std::string& token) {
  return {{"tool", tool},          {"version", kVersion}, {"state", "writing"}, {"token", token}, {"pid", static_cast<long>(::getpid())},
          {"started_ns", now_ns()}};
}

std::int64_t mtime_ns(const fs::path& p) {
  std::error_code ec;
  const auto t = fs::last_write_time(p, ec);
  return ec ? 0 : static_cast<std::int64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count());
}

json file_entry(const fs::path& p) {
  std::error_code ec;
  return {{"size", static_cast<std::uintmax_t>(fs::file_size(p, ec))}, {"hash", file_hash(p)}};
}

// Whether the file at `p` is the one a manifest entry describes: by content hash; entries of
// manifests written before hashes were recorded, by size and modification time.
bool entry_matches(const json& entry, const fs::path& p) {
  if (!entry.is_object()) return false;
  std::error_code ec;
  const auto size = fs::file_size(p, ec);
  if (ec || entry.value("size", std::uintmax_t{0}) != size) return false;
  if (entry.contains("hash")) return entry["hash"].is_string() && entry["hash"].get<std::string>() == file_hash(p);
  return entry.value("mtime_ns", std::int64_t{-1}) == mtime_ns(p);
}

bool is_complete_marker(const json& m) { return !m.is_null() && m.value("state", "") == "complete" && m.contains("files") && m["files"].is_object(); }

// ---------------------------------------------------------------------------------------------
fs::path absolute_path(const fs::path& p) {
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
  std::error_code ec;
  if (final == absolute_path(fs::current_path(ec)))
    throw WriteError(final.string(), "it is the current folder; tactus writes its " + kind +
                                         " into a new folder (e.g. -o results) and never replaces the folder you work in");
  for (const auto& input : rules.inputs) {
    if (input.empty()) continue;
    const fs::path in = absolute_path(input);
    if (in == final) throw WriteError(final.string(), "it is an input of this run (" + input.string() + "); choose another output");
    if (is_same_or_ancestor(final, in))
      throw WriteError(final.string(), "it contains an input of this run (" + input.string() + "); tactus would replace it: choose a new folder");
  }
}

// ---------------------------------------------------------------------------------------------
// What is in a previous output folder, against its manifest.
struct Existing {
  bool present = false;              // a non-empty folder
  json marker;                       // its manifest
  std::vector<std::string> files;    // listed files, unchanged
  std::vector<std::string> dirs;     // folders tactus made (listed, or holding a listed file)
  std::vector<std::string> foreign;  // top-most entries tactus did not write: kept in place
  std::vector<std::string> edited;   // listed files whose content changed since
};

// The folders a manifest accounts for: those it lists and those holding a listed file.
std::set<std::string> manifest_dirs(const json& marker) {
  std::set<std::string> dirs;
  if (marker.contains("dirs") && marker["dirs"].is_array())
    for (const auto& d : marker["dirs"])
      if (d.is_string()) dirs.insert(d.get<std::string>());
  for (const auto& [name, entry] : marker["files"].items())
    for (fs::path p = fs::path(name).parent_path(); !p.empty(); p = p.parent_path()) dirs.insert(p.generic_string());
  return dirs;
}

Existing classify(const fs::path& folder, const json& marker) {
  Existing e;
  e.present = true;
  e.marker = marker;
  const json& listed = marker["files"];
  const std::set<std::string> dirs = manifest_dirs(marker);
  std::vector<fs::path> pending{fs::path()};
  while (!pending.empty()) {
    const fs::path rel_dir = pending.back();
    pending.pop_back();
    std::error_code ec;
    fs::directory_iterator it(folder / rel_dir, ec);
    if (ec) throw WriteError((folder / rel_dir).string(), "cannot read the folder to see what is in it", ec.value());
    std::vector<fs::directory_entry> entries(it, fs::directory_iterator());
    std::sort(entries.begin(), entries.end());
    for (const auto& entry : entries) {
      const fs::path rel = rel_dir / entry.path().filename();
      const std::string name = rel.generic_string();
      if (name == kFolderMarker || name == kLockFile) continue;
      if (name == kFilesMarker) {  // tactus's list of files written here by output-file tools: goes with the output
        e.files.push_back(name);
        continue;
      }
      const auto st = entry.symlink_status(ec);
      if (fs::is_directory(st)) {
        if (dirs.count(name)) {
          e.dirs.push_back(name);
          pending.push_back(rel);
        } else {
          e.foreign.push_back(name);
        }
      } else if (fs::is_regular_file(st) && listed.contains(name)) {
        (entry_matches(listed[name], entry.path()) ? e.files : e.edited).push_back(name);
      } else {
        e.foreign.push_back(name);  // an unlisted file, a link, a FIFO, ...
      }
    }
  }
  return e;
}

std::string first_entry(const fs::path& dir) {
  std::error_code ec;
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir, ec)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names.empty() ? "" : names.front();
}

std::string list_names(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t i = 0; i < names.size() && i < 5; ++i) s += (i ? ", '" : "'") + names[i] + "'";
  if (names.size() > 5) s += " and " + std::to_string(names.size() - 5) + " more";
  return s;
}

// What is at `final` (a folder), or WriteError unless an output of rules.tool may replace it.
Existing check_folder_replaceable(const fs::path& final, const OutputRules& rules) {
  std::error_code ec;
  const auto st = fs::symlink_status(final, ec);
  if (!fs::exists(st)) return {};
  if (fs::is_symlink(st)) throw WriteError(final.string(), "it is a link; give the folder itself, or a new folder");
  if (!fs::is_directory(st)) throw WriteError(final.string(), "it is a file, not a folder; choose a new folder");
  if (fs::is_empty(final, ec)) return {};
  const json marker = read_marker(final / kFolderMarker);
  if (!is_complete_marker(marker)) {
    std::size_t n = 0;
    for (auto it = fs::directory_iterator(final, ec); !ec && it != fs::directory_iterator(); it.increment(ec)) ++n;
    throw WriteError(final.string(), "it is a folder tactus did not write (" + std::to_string(n) + " entries, e.g. '" + first_entry(final) +
                                         "'); tactus never replaces it: choose a new or empty folder");
  }
  const std::string writer = marker.value("tool", "");
  if (writer != rules.tool && !rules.force)
    throw WriteError(final.string(),
                     "it holds the output of " + writer + ", not of " + rules.tool + "; give --force to replace it, or choose another folder");
  Existing e = classify(final, marker);
  if (!e.edited.empty())
    throw WriteError(final.string(), list_names(e.edited) + " in it changed since " + writer +
                                         " wrote it; tactus does not overwrite your edits: move or rename it, or choose another folder");
  return e;
}

// Moves the entries tactus did not write from the previous output `old` into the new one at
// `final`, then removes what the previous manifest listed. Returns what was kept in place.
std::vector<std::string> finish_replacement(const fs::path& final, const fs::path& old, const Existing& e) {
  std::error_code ec;
  for (const std::string& name : e.foreign) {
    const fs::path target = final / name;
    fs::create_directories(target.parent_path(), ec);
    fs::rename(old / name, target, ec);
    if (ec) throw WriteError(target.string(), "cannot keep it in place (" + ec.message() + "); it is still in " + old.string());
  }
  for (const std::string& name : e.files) fs::remove(old / name, ec);
  std::vector<std::string> dirs = e.dirs;
  std::sort(dirs.rbegin(), dirs.rend());                      // deepest first
  for (const std::string& d : dirs) fs::remove(old / d, ec);  // only when empty
  fs::remove(old / kFolderMarker, ec);
  fs::remove(old / kLockFile, ec);
  if (!fs::remove(old, ec) && fs::exists(old))
    log::warn(old.string() + " still holds entries tactus did not expect there (e.g. '" + first_entry(old) + "'): kept, look into it");
  sync_directory(final);
  return e.foreign;
}

void say_kept(const fs::path& final, const std::vector<std::string>& kept) {
  if (!kept.empty())
    log::info() << "kept " << kept.size() << (kept.size() == 1 ? " entry" : " entries") << " tactus did not write, in place in " << final.string()
                << ": " << list_names(kept);
}

// renameat2 with a flag; false (errno set) when it failed.
bool rename_with(const fs::path& from, const fs::path& to, unsigned flags) {
  return ::renameat2(AT_FDCWD, from.c_str(), AT_FDCWD, to.c_str(), flags) == 0;
}

// Publishes the complete output in `staging` (its manifest `marker`, without "replaces") at
// `final`. The staging folder holds its lock file (taken by this process).
void publish(const fs::path& staging, const fs::path& final, const OutputRules& rules, json marker) {
  const Existing old = check_folder_replaceable(final, rules);
  // The user's entries in the previous output stay where they are: the new output must not hold one of their names.
  for (const std::string& name : old.foreign)
    for (fs::path p = name; !p.empty(); p = p.parent_path()) {
      std::error_code ec;
      const auto st = fs::symlink_status(staging / p, ec);
      if (fs::exists(st) && (p != fs::path(name) ? !fs::is_directory(st) : true))
        throw WriteError(final.string(),
                         "'" + name + "' in it was not written by tactus, and the new output has an entry of that name; move it away");
    }
  std::error_code ec;
  const bool replace = fs::exists(fs::symlink_status(final, ec));
  const fs::path parent = final.parent_path();
  if (!replace) {
    write_json_atomically(staging / kFolderMarker, marker);
    if (!rename_with(staging, final, RENAME_NOREPLACE)) {
      const int err = errno;
      if (err != EINVAL && err != ENOSYS) throw WriteError(final.string(), "cannot move the output into place", err);
      fs::rename(staging, final, ec);  // a file system without renameat2 flags
      if (ec) throw WriteError(final.string(), "cannot move the output into place", ec.value());
    }
    sync_directory(parent);
    fs::remove(final / kLockFile, ec);
    return;
  }
  // The previous output (or the empty folder) goes to where the staging folder was: the new
  // manifest says so first, so a process killed after the swap leaves enough to finish it.
  fs::path aside = staging;
  marker["replaces"] = aside.filename().string();
  write_json_atomically(staging / kFolderMarker, marker);
  if (!rename_with(staging, final, RENAME_EXCHANGE)) {
    const int err = errno;
    if (err != EINVAL && err != ENOSYS) throw WriteError(final.string(), "cannot move the output into place", err);
    // No atomic exchange on this file system: two renames, the manifest naming where the old one goes.
    aside = parent / (final.filename().string() + ".replaced-" + unique_suffix());
    marker["replaces"] = aside.filename().string();
    write_json_atomically(staging / kFolderMarker, marker);
    fs::rename(final, aside, ec);
    if (ec) throw WriteError(final.string(), "cannot move the previous output aside", ec.value());
    fs::rename(staging, final, ec);
    if (ec) {
      std::error_code back;
      fs::rename(aside, final, back);
      throw WriteError(final.string(), "cannot move the output into place", ec.value());
    }
  }
  sync_directory(parent);
  test_kill_point("swapped");
  std::vector<std::string> kept;
  try {
    if (old.present) kept = finish_replacement(final, aside, old);
  } catch (const Error& e) {
    // The new output is in place; what is left of the previous one is finished by the next run.
    log::warn(std::string(e.what()) + "; the rest of the previous output is in " + aside.string() + " until the next run writing " + final.string() +
              " sorts it");
    return;
  }
  if (!old.present) fs::remove(aside, ec);  // the empty folder that was there
  marker.erase("replaces");
  write_json_atomically(final / kFolderMarker, marker);
  fs::remove(final / kLockFile, ec);
  sync_directory(final);
  say_kept(final, kept);
}

// ---------------------------------------------------------------------------------------------
// Staging folders `<name>.partial-*` of an output.
struct Staging {
  fs::path path;
  json marker;
};

std::vector<Staging> sibling_staging(const fs::path& final) {
  std::vector<Staging> found;
  const std::string prefix = final.filename().string() + ".partial-";
  std::error_code ec;
  for (auto it = fs::directory_iterator(final.parent_path(), ec); !ec && it != fs::directory_iterator(); it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(prefix, 0) != 0 || !it->is_directory(ec) || it->is_symlink(ec)) continue;
    json m = read_marker(it->path() / kFolderMarker);
    if (m.is_null()) continue;  // being created, or not tactus's: never touched
    found.push_back({it->path(), std::move(m)});
  }
  std::sort(found.begin(), found.end(), [](const Staging& a, const Staging& b) { return a.path < b.path; });
  return found;
}

// A killed commit at `final`: the new output's manifest names where the previous output went.
void finish_pending_replacement(const fs::path& final) {
  const json marker = read_marker(final / kFolderMarker);
  int fd = -1;
  const LockState lock = try_lock(final, fd);
  if (lock == LockState::held)
    throw WriteError(final.string(), "another tactus tool is moving its output into place there right now; wait for it to finish");
  std::error_code ec;
  if (marker.is_null() || !marker.contains("replaces") || !marker["replaces"].is_string()) {
    if (lock == LockState::taken) fs::remove(final / kLockFile, ec);  // left by a process killed just after its rename
    release(fd);
    return;
  }
  const fs::path old = final.parent_path() / marker["replaces"].get<std::string>();
  std::vector<std::string> kept;
  const json old_marker = read_marker(old / kFolderMarker);
  if (fs::is_directory(old, ec)) {
    if (is_complete_marker(old_marker)) {
      Existing e = classify(old, old_marker);
      e.foreign.insert(e.foreign.end(), e.edited.begin(), e.edited.end());  // a changed file is the user's now: kept
      e.edited.clear();
      kept = finish_replacement(final, old, e);
    } else if (fs::is_empty(old, ec)) {
      fs::remove(old, ec);
    } else {
      log::warn("the output that " + final.string() + " replaced is still in " + old.string() + " (no readable manifest): kept, look into it");
    }
  }
  json done = marker;
  done.erase("replaces");
  write_json_atomically(final / kFolderMarker, done);
  fs::remove(final / kLockFile, ec);
  release(fd);
  log::info() << "finished putting the output of an interrupted " << marker.value("tool", "tactus") << " run into place in " << final.string();
  say_kept(final, kept);
}

// Staging folders whose process is gone: a complete one (killed between finishing and the
// swap) is published when the rules allow it; one still being written is removed unless it can
// be continued (checkpoints). Staging folders of live processes are left alone.
void recover_staging(const fs::path& final) {
  for (const Staging& s : sibling_staging(final)) {
    int fd = -1;
    if (try_lock(s.path, fd) != LockState::taken) continue;  // alive, or not ours to judge (no lock file)
    std::error_code ec;
    const std::string state = s.marker.value("state", "");
    // Its own output, by the token in its name (a previous output moved aside here by a swap has another).
    const std::string prefix = final.filename().string() + ".partial-";
    const bool own = s.marker.value("token", "") == s.path.filename().string().substr(prefix.size());
    if (state == "complete" && own && !s.marker.contains("replaces")) {
      try {
        publish(s.path, final, {s.marker.value("tool", ""), {}, false}, s.marker);
        log::info() << "published the finished output of an interrupted " << s.marker.value("tool", "tactus") << " run at " << final.string();
      } catch (const Error& e) {
        log::warn("the finished output of an interrupted run is kept in " + s.path.string() + ": " + e.what());
      }
    } else if (state == "writing" && !fs::is_directory(s.path / kResumableDir, ec)) {
      fs::remove_all(s.path, ec);
    }
    release(fd);
  }
}

// Refuses when another live process writes `final` and started first (the later of two refuses).
void require_single_writer(const fs::path& final, const fs::path& own, const json& own_marker) {
  for (const Staging& s : sibling_staging(final)) {
    if (s.path == own) continue;
    int fd = -1;
    const LockState lock = try_lock(s.path, fd);
    release(fd);
    if (lock != LockState::held) continue;
    const auto key = [](const json& m) { return std::make_pair(m.value("started_ns", std::int64_t{0}), m.value("token", std::string())); };
    if (key(s.marker) <= key(own_marker))
      throw WriteError(final.string(), "another " + s.marker.value("tool", std::string("tactus tool")) + " (pid " +
                                           std::to_string(s.marker.value("pid", 0L)) + ") is writing this output right now (" + s.path.string() +
                                           "); wait for it to finish, or choose another output");
  }
}

// Creates a staging folder `<final>.partial-<token>` with its lock (taken) and its "writing" marker.
fs::path create_staging(const fs::path& final, const std::string& tool, int& lock, json& marker) {
  const std::string token = unique_suffix();
  const fs::path staging = final.parent_path() / (final.filename().string() + ".partial-" + token);
  std::error_code ec;
  fs::create_directory(staging, ec);
  if (ec) throw WriteError(staging.parent_path().string(), "cannot create a folder there", ec.value());
  register_staging_path(staging);
  try {
    lock = create_lock(staging);
    marker = staging_marker(tool, token);
    write_json_atomically(staging / kFolderMarker, marker);
  } catch (...) {
    release(lock);
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
                                         " is free there (no space left on device); free some space or write elsewhere");
}

void discard_staging(fs::path& staging, int& lock) {
  if (staging.empty()) return;
  std::error_code ec;
  fs::remove_all(staging, ec);
  unregister_staging_path(staging);
  release(lock);
}

// Every regular file under `dir` (relative path -> size and hash) and every folder, each file
// flushed to the disk first: what the manifest of a new output lists.
void snapshot(const fs::path& dir, json& files, json& dirs) {
  files = json::object();
  dirs = json::array();
  std::error_code ec;
  std::vector<fs::path> all;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator(); it.increment(ec))
    all.push_back(it->path());
  if (ec) throw WriteError(dir.string(), "cannot list what was written", ec.value());
  std::sort(all.begin(), all.end());
  for (const fs::path& p : all) {
    const std::string rel = p.lexically_relative(dir).generic_string();
    if (rel == kFolderMarker || rel == kLockFile || rel == kFilesMarker) continue;
    const auto st = fs::symlink_status(p, ec);
    if (fs::is_directory(st)) {
      dirs.push_back(rel);
      sync_directory(p);
    } else if (fs::is_regular_file(st)) {
      sync_file(p);
      files[rel] = file_entry(p);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Output files: the manifest of a directory (files tactus wrote there). A directory that is itself
// a complete tactus output folder lends its manifest's top-level files, so they are recognised
// as tactus's too.
json read_files_manifest(const fs::path& dir) {
  const fs::path p = dir / kFilesMarker;
  std::error_code ec;
  json m = json{{"files", json::object()}};
  if (fs::exists(p, ec)) {
    m = read_marker(p);
    if (m.is_null() || !m.contains("files") || !m["files"].is_object())
      throw WriteError(p.string(), "it is not a tactus output list (unreadable); move it away");
  }
  const json folder = read_marker(dir / kFolderMarker);
  if (is_complete_marker(folder))
    for (const auto& [name, entry] : folder["files"].items())
      if (name.find('/') == std::string::npos && !m["files"].contains(name) && entry.is_object()) {
        json e = entry;
        e["tool"] = folder.value("tool", "");
        m["files"][name] = e;
      }
  return m;
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
  if (!entry_matches(entry, final))
    throw WriteError(final.string(), "the file changed since tactus wrote it; tactus does not overwrite your edits: move or rename it");
  const std::string writer = entry.value("tool", "");
  if (writer != rules.tool && !rules.force)
    throw WriteError(final.string(), "it was written by " + writer + ", not by " + rules.tool + "; give --force to replace it");
}

// Records files just moved into `dir` in its manifest (and in the folder manifest of `dir` when it
// is an output folder), under a lock on the folder so two tools finishing at once keep both.
void record_files(const fs::path& dir, const json& entries) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) ::flock(fd, LOCK_EX);
  try {
    json manifest = read_files_manifest(dir);
    for (const auto& [name, entry] : entries.items()) manifest["files"][name] = entry;
    write_json_atomically(dir / kFilesMarker, manifest);
    json folder = read_marker(dir / kFolderMarker);
    if (is_complete_marker(folder)) {
      for (const auto& [name, entry] : entries.items()) folder["files"][name] = json{{"size", entry["size"]}, {"hash", entry["hash"]}};
      write_json_atomically(dir / kFolderMarker, folder);
    }
    sync_directory(dir);
  } catch (...) {
    if (fd >= 0) ::close(fd);
    throw;
  }
  if (fd >= 0) ::close(fd);
}

// Moves the staged files of a commit into `dir` (those still staged: a killed commit may have
// moved some) and records them.
void move_staged_files(const fs::path& staging, const fs::path& dir, const json& entries) {
  for (const auto& [name, entry] : entries.items()) {
    std::error_code ec;
    if (!fs::exists(staging / name, ec)) continue;
    fs::rename(staging / name, dir / name, ec);
    if (ec) throw WriteError((dir / name).string(), "cannot move the file into place", ec.value());
  }
  record_files(dir, entries);
}

// Commits of output files a killed process left half done (their staging says "committing").
void recover_file_commits(const fs::path& first_final) {
  for (const Staging& s : sibling_staging(first_final)) {
    int fd = -1;
    if (try_lock(s.path, fd) != LockState::taken) continue;
    std::error_code ec;
    const std::string state = s.marker.value("state", "");
    if (state == "committing" && s.marker.contains("files") && s.marker["files"].is_object()) {
      move_staged_files(s.path, first_final.parent_path(), s.marker["files"]);
      log::info() << "finished putting the files of an interrupted " << s.marker.value("tool", "tactus") << " run into place in "
                  << first_final.parent_path().string();
      fs::remove_all(s.path, ec);
    } else if (state == "writing") {
      fs::remove_all(s.path, ec);
    }
    release(fd);
  }
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

fs::path normalise_output_path(const fs::path& given, const std::string& kind) {
  std::string s = given.string();
  if (s.empty()) throw InputError("command line", "-o/--output", "an output " + kind, "an empty path");
  while (s.size() > 1 && s.back() == '/') s.pop_back();
  const fs::path p(s);
  const fs::path name = p.filename();
  if (name == ".")
    throw WriteError(given.string(), "it is the current folder; tactus writes its output " + kind +
                                         " into a new folder (e.g. -o results) and never replaces the folder you work in");
  if (s == "/" || name.empty() || name == "..") throw WriteError(given.string(), "an output " + kind + " path must end in a name (e.g. -o results)");
  fs::path parent = p.parent_path();
  if (parent.empty()) parent = ".";
  std::error_code ec;
  fs::create_directories(parent, ec);  // as the kernel resolves it: "a/missing/../b" makes a/missing
  if (!fs::is_directory(parent, ec))
    throw WriteError(given.string(), "cannot create its folder " + parent.string() + " (" + (ec ? ec.message() : describe_file_type(parent)) + ")");
  const fs::path resolved = fs::canonical(parent, ec);
  if (ec) throw WriteError(given.string(), "cannot resolve its folder " + parent.string() + " (" + ec.message() + ")");
  const fs::path final = resolved / name;
  if (fs::is_symlink(fs::symlink_status(final, ec)))
    throw WriteError(given.string(), "it is a link (to " + fs::read_symlink(final, ec).string() +
                                         "); tactus does not write through links: give the folder itself, or a new name");
  return final;
}

// ---------------------------------------------------------------------------------------------
OutputFolder::OutputFolder(fs::path folder, OutputRules rules, const fs::path& resume) : rules_(std::move(rules)) {
  final_ = normalise_output_path(folder, "folder");
  check_place(final_, rules_, "output folder");
  finish_pending_replacement(final_);
  recover_staging(final_);
  check_folder_replaceable(final_, rules_);
  json marker;
  if (resume.empty()) {
    staging_ = create_staging(final_, rules_.tool, lock_, marker);
  } else {
    // The killed run's staging folder becomes this process's: its lock taken, its marker ours.
    const fs::path candidate = absolute_path(resume);
    const json m = read_marker(candidate / kFolderMarker);
    const bool sibling =
        candidate.parent_path() == final_.parent_path() && candidate.filename().string().rfind(final_.filename().string() + ".partial-", 0) == 0;
    if (!sibling || m.is_null() || m.value("tool", "") != rules_.tool || try_lock(candidate, lock_) != LockState::taken)
      throw InputError(resume.string(), "", "the staging folder of a killed " + rules_.tool + " run writing " + final_.string(),
                       "not one (its process still runs, or it belongs elsewhere)");
    staging_ = candidate;
    register_staging_path(staging_);
    marker = staging_marker(rules_.tool, m.value("token", unique_suffix()));
    write_json_atomically(staging_ / kFolderMarker, marker);
  }
  try {
    require_single_writer(final_, staging_, marker);
  } catch (...) {
    if (resume.empty()) {
      discard_staging(staging_, lock_);
    } else {
      unregister_staging_path(staging_);
      release(lock_);
    }
    throw;
  }
}

OutputFolder::~OutputFolder() {
  if (!committed_ && !kept_) discard_staging(staging_, lock_);
  release(lock_);
}

void OutputFolder::keep_for_resume() {
  kept_ = true;
  unregister_staging_path(staging_);
}

std::vector<fs::path> resumable_staging(const fs::path& folder, const std::string& tool, bool probe_locks) {
  std::vector<fs::path> found;
  fs::path final;
  try {
    final = normalise_output_path(folder, "folder");
  } catch (const Error&) {
    return found;
  }
  for (const Staging& s : sibling_staging(final)) {
    if (s.marker.value("tool", "") != tool || s.marker.value("state", "") != "writing") continue;
    std::error_code ec;
    if (!fs::is_directory(s.path / kResumableDir, ec)) continue;
    if (!probe_locks) {
      found.push_back(s.path);
      continue;
    }
    int fd = -1;
    const LockState lock = try_lock(s.path, fd);
    release(fd);
    if (lock == LockState::taken) found.push_back(s.path);
  }
  return found;
}

void OutputFolder::require_space(std::uintmax_t bytes, const std::string& what) const { check_space(staging_, bytes, what, final_); }

void OutputFolder::commit() {
  check_interrupt();
  json marker = {{"tool", rules_.tool}, {"version", kVersion}, {"state", "complete"}, {"written_utc", utc_now()}};
  const json writing = read_marker(staging_ / kFolderMarker);
  marker["token"] = writing.is_null() ? unique_suffix() : writing.value("token", unique_suffix());
  snapshot(staging_, marker["files"], marker["dirs"]);
  write_json_atomically(staging_ / kFolderMarker, marker);  // complete: a kill from here on publishes it next time
  test_kill_point("complete");
  check_interrupt();
  // From here the staging path is no longer this run's to remove: after the swap it holds the
  // previous output (the interrupt watcher must not delete it on a forced exit).
  unregister_staging_path(staging_);
  try {
    publish(staging_, final_, rules_, marker);
  } catch (const Error& e) {
    kept_ = true;  // the complete output is not thrown away
    throw WriteError(final_.string(), std::string(e.what()) + " (the new output is complete in " + staging_.string() +
                                          "; it is put into place by the next run writing there once this is mended)");
  }
  committed_ = true;
}

// ---------------------------------------------------------------------------------------------
OutputFiles::OutputFiles(std::vector<fs::path> files, OutputRules rules) : rules_(std::move(rules)) {
  if (files.empty()) throw InputError("command line", "-o/--output", "an output file");
  for (const auto& f : files) finals_.push_back(normalise_output_path(f, "file"));
  dir_ = finals_.front().parent_path();
  for (std::size_t i = 0; i < finals_.size(); ++i) {
    check_place(finals_[i], rules_, "output file");
    if (finals_[i].parent_path() != dir_) throw InputError("command line", "-o/--output", "output files in one folder", files[i].string());
    std::error_code ec;
    if (fs::is_directory(finals_[i], ec))
      throw WriteError(files[i].string(), "it is a folder; give a file name (or a folder output without the extension)");
  }
  recover_file_commits(finals_.front());
  const json manifest = read_files_manifest(dir_);
  for (const auto& f : finals_) check_file_replaceable(f, rules_, manifest);
  json marker;
  staging_ = create_staging(finals_.front(), rules_.tool, lock_, marker);
  try {
    require_single_writer(finals_.front(), staging_, marker);
  } catch (...) {
    discard_staging(staging_, lock_);
    throw;
  }
}

OutputFiles::~OutputFiles() {
  if (!committed_) discard_staging(staging_, lock_);
  release(lock_);
}

fs::path OutputFiles::staged(std::size_t i) const { return staging_ / finals_.at(i).filename(); }

void OutputFiles::require_space(std::uintmax_t bytes, const std::string& what) const { check_space(staging_, bytes, what, finals_.front()); }

void OutputFiles::commit() {
  check_interrupt();
  json entries = json::object();
  for (std::size_t i = 0; i < finals_.size(); ++i) {
    std::error_code ec;
    if (!fs::is_regular_file(staged(i), ec)) throw WriteError(finals_[i].string(), "the tool wrote nothing there (internal error)");
    sync_file(staged(i));
    json entry = file_entry(staged(i));
    entry["tool"] = rules_.tool;
    entries[finals_[i].filename().string()] = entry;
  }
  const json manifest = read_files_manifest(dir_);
  for (const auto& f : finals_) check_file_replaceable(f, rules_, manifest);
  check_interrupt();
  // The journal: a process killed while moving the files leaves what the next run needs to finish.
  json marker = read_marker(staging_ / kFolderMarker);
  if (marker.is_null()) marker = json::object();
  marker["state"] = "committing";
  marker["files"] = entries;
  write_json_atomically(staging_ / kFolderMarker, marker);
  unregister_staging_path(staging_);  // a forced exit now leaves the journal for the next run to finish
  move_staged_files(staging_, dir_, entries);
  committed_ = true;
  std::error_code ec;
  fs::remove_all(staging_, ec);
  release(lock_);
}

}  // namespace tactus
