#pragma once
// One file written under a temporary name next to its final place and renamed only when
// complete, so a crash or an error never leaves a half-written file that looks finished. The
// file writers (write_msh, write_vtu, write_h5, ...) use it; a tool's whole output goes through
// OutputFolder / OutputFiles (output.hpp), which decide whether the final place may be used.
#include <filesystem>
#include <string>
#include <string_view>

namespace tactus {

class StagedOutput {
 public:
  // The staging path is a sibling "<name>.partial-<pid>-<random>" (same file system: the rename
  // is atomic; no other process, whatever its pid, picks the same name).
  explicit StagedOutput(std::filesystem::path final_path);
  ~StagedOutput();  // removes the staging file unless committed
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;

  const std::filesystem::path& path() const noexcept { return staging_; }
  const std::filesystem::path& final_path() const noexcept { return final_; }
  // Flushes the staged file to the disk (checked), checks that it ends with `tail` when one is
  // given (a third-party writer's format end: a file cut short by a full disk is caught), renames
  // it to the final path (replacing a file there; never a folder) and flushes the folder.
  void commit(std::string_view tail = {}, const std::string& format = {});

 private:
  std::filesystem::path final_, staging_;
  bool committed_ = false;
};

// Creates the parent directory of `path` if needed; throws WriteError when it cannot.
void ensure_parent_directory(const std::filesystem::path& path);

}  // namespace tactus
