#pragma once
// Where a tactus tool writes its results (its -o), with one promise: tactus never deletes or
// overwrites a file it did not write.
//
// A tool's output is either a folder (OutputFolder: tactus-solve's results, tactus-post's report,
// ...) or a few files in one directory (OutputFiles: tactus-mesh box -o block.msh writes
// block.msh, block.vtu and block_quality.json). Everything is written into a staging folder next
// to the final place, `<name>.partial-<pid>-<random>`, and moved into place by commit(), so a
// failure or an interrupt never leaves a half-written output looking complete.
//
// The output path is made absolute and its parent folder resolved (and created) before any work,
// so a trailing slash, a `..` after a missing folder or a link in the parent cannot fail a run at
// its end. The final place may be new, an empty folder, or a previous output of the same tool,
// recognised by the manifest tactus writes there: `.tactus-output.json` inside an output folder,
// `.tactus-outputs.json` in the directory of output files. The manifest lists every file tactus
// wrote with its size and content hash, and every folder it made. Replacing a previous output
// replaces only what the manifest lists, as written: anything else in the folder (a user's notes,
// an empty folder, a link) is kept in place and named in the log, and a listed file whose content
// changed since (a user's edit) makes the tool refuse before any work, naming it. `force` also
// replaces a previous output of another tactus tool; a folder without a manifest is never used.
// The output may not be the current folder, nor any input, nor a folder containing an input.
//
// One writer at a time: each staging folder holds a lock (flock on `.tactus-lock` in it) for as
// long as its process lives. A second tool writing the same output while the first holds its lock
// refuses. A staging folder whose lock is free belongs to a process that is gone (never judged by
// a pid, which another namespace or a later process may reuse): it is removed by the next run
// writing the same output, except one holding a `checkpoints/` folder (kResumableDir), which a
// killed solve can be continued from (tactus-solve --restart OUT).
//
// The commit swaps the new output in with one atomic exchange (renameat2 RENAME_EXCHANGE), so
// there is no moment without an output at the final path, and records in the new manifest where
// the previous output went. A process killed before the swap leaves a complete staging folder,
// which the next run writing there publishes; one killed after it leaves the previous output
// beside the new one, which the next run finishes sorting (the user's entries moved over, the
// listed files removed).
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace tactus {

struct OutputRules {
  std::string tool;                           // "tactus-solve": recorded in the marker
  std::vector<std::filesystem::path> inputs;  // what the tool reads: the output may not be or contain one
  bool force = false;                         // also replace a previous output of another tactus tool
};

// Marker (manifest) file names, and the lock file of a staging folder.
inline constexpr const char* kFolderMarker = ".tactus-output.json";
inline constexpr const char* kFilesMarker = ".tactus-outputs.json";
inline constexpr const char* kLockFile = ".tactus-lock";
inline constexpr const char* kResumableDir = "checkpoints";

class OutputFolder {
 public:
  // Normalises the path, finishes a commit a killed run left half done, checks the rules and
  // that the place is writable, creates and locks the staging folder (throws InputError /
  // WriteError naming the path otherwise). Nothing at `folder` is touched yet.
  // `resume`: continue in the staging folder of a killed run of the same tool writing `folder`
  // (one of resumable_staging()), which becomes this process's.
  OutputFolder(std::filesystem::path folder, OutputRules rules, const std::filesystem::path& resume = {});
  ~OutputFolder();  // removes the staging folder unless committed or kept
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  const std::filesystem::path& path() const noexcept { return staging_; }  // write here
  const std::filesystem::path& final_path() const noexcept { return final_; }
  // Refuses (WriteError) when the file system holding the output has less than `bytes` free.
  void require_space(std::uintmax_t bytes, const std::string& what) const;
  // Refuses (Interrupted) when a stop signal arrived, flushes every file to the disk, records
  // them in the manifest and moves the folder into place, replacing what the previous output of
  // this tool listed (re-checked now: the run may have taken hours). When that re-check fails
  // the complete output stays in its staging folder, named in the error.
  void commit();
  // Leaves the staging folder in place when the process ends without committing (an interrupted
  // run with a checkpoint in it, to be continued later).
  void keep_for_resume();

 private:
  std::filesystem::path final_, staging_;
  OutputRules rules_;
  int lock_ = -1;
  bool committed_ = false, kept_ = false;
};

// The staging folders of killed runs of `tool` writing `folder` that hold a kResumableDir, in name order.
// probe_locks = false: every such folder whose marker says "writing", its lock not tried (a second
// process that only reads what the first one found: two probing at once would each see the other's
// probe as a live writer).
std::vector<std::filesystem::path> resumable_staging(const std::filesystem::path& folder, const std::string& tool, bool probe_locks = true);

class OutputFiles {
 public:
  // `files`: the final paths, all in one directory.
  OutputFiles(std::vector<std::filesystem::path> files, OutputRules rules);
  ~OutputFiles();
  OutputFiles(const OutputFiles&) = delete;
  OutputFiles& operator=(const OutputFiles&) = delete;

  std::filesystem::path staged(std::size_t i) const;  // write file i here
  const std::vector<std::filesystem::path>& final_paths() const noexcept { return finals_; }
  void require_space(std::uintmax_t bytes, const std::string& what) const;
  void commit();

 private:
  std::vector<std::filesystem::path> finals_;
  std::filesystem::path dir_, staging_;
  OutputRules rules_;
  int lock_ = -1;
  bool committed_ = false;
};

// The output path as tactus uses it: absolute, the parent folder resolved through links (and
// created when missing), no trailing separator. InputError / WriteError naming the path when it
// ends in "." or "..", when its last component is a link, or when the parent cannot be made.
std::filesystem::path normalise_output_path(const std::filesystem::path& given, const std::string& kind);

// "12.3 MB", for messages.
std::string human_bytes(std::uintmax_t bytes);

}  // namespace tactus
