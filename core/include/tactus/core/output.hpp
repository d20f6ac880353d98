#pragma once
// Where a tactus tool writes its results (its -o), with one promise: tactus never deletes or
// overwrites a file it did not write.
//
// A tool's output is either a folder (OutputFolder: tactus-solve's results, tactus-post's report,
// ...) or a few files in one directory (OutputFiles: tactus-mesh box -o block.msh writes
// block.msh, block.vtu and block_quality.json). Everything is written into a staging folder next
// to the final place, `<name>.partial-<pid>`, and moved into place by commit(), so a failure or an
// interrupt never leaves a half-written output looking complete.
//
// The final place may be new or an empty folder. It may also be a previous output of the same
// tool, recognised by the marker tactus writes: `.tactus-output.json` inside an output folder,
// `.tactus-outputs.json` in the directory of output files. The marker lists every file with its
// size and modification time, so a previous output is replaced only while it holds exactly what
// tactus wrote there; a file a user added or edited is never deleted (the tool refuses and names
// it). `force` also replaces a previous output of another tactus tool, never a foreign one. The
// output may not be the current folder, nor any input, nor a folder containing an input.
//
// Stale staging folders of dead processes (a killed run) are removed by the next run that writes
// the same output, except those holding a `checkpoints/` folder (kResumableDir): a killed solve
// that can be continued (tactus-solve --restart OUT) is never thrown away.
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

// Marker file names.
inline constexpr const char* kFolderMarker = ".tactus-output.json";
inline constexpr const char* kFilesMarker = ".tactus-outputs.json";
inline constexpr const char* kResumableDir = "checkpoints";

class OutputFolder {
 public:
  // Checks the rules and that the place is writable, creates the staging folder (throws
  // InputError / WriteError naming the path otherwise). Nothing at `folder` is touched yet.
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
  // Records every file in the marker and moves the folder into place (replacing the previous
  // output of this tool, re-checked now: the run may have taken hours).
  void commit();
  // Leaves the staging folder in place when the process ends without committing (an interrupted
  // run with a checkpoint in it, to be continued later).
  void keep_for_resume();

 private:
  std::filesystem::path final_, staging_;
  OutputRules rules_;
  bool committed_ = false, kept_ = false;
};

// The staging folders of killed runs of `tool` writing `folder` that hold a kResumableDir, in name order.
std::vector<std::filesystem::path> resumable_staging(const std::filesystem::path& folder, const std::string& tool);

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
  bool committed_ = false;
};

// "12.3 MB", for messages.
std::string human_bytes(std::uintmax_t bytes);

}  // namespace tactus
