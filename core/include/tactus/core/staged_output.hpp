#pragma once
// Outputs are written under a temporary name next to their final place and renamed only when
// complete, so a crash or an error never leaves a half-written file that looks finished.
#include <filesystem>

namespace tactus {

class StagedOutput {
 public:
  // `final_path` may be a file or a directory; the staging path is a sibling with a
  // ".partial" suffix (same filesystem, so the rename is atomic for files).
  explicit StagedOutput(std::filesystem::path final_path);
  ~StagedOutput();  // removes the staging path unless committed
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;

  const std::filesystem::path& path() const noexcept { return staging_; }
  const std::filesystem::path& final_path() const noexcept { return final_; }
  // Replaces any previous output at the final path with the staged one.
  void commit();

 private:
  std::filesystem::path final_, staging_;
  bool committed_ = false;
};

// Creates the parent directory of `path` if needed; throws InputError when it cannot.
void ensure_parent_directory(const std::filesystem::path& path);

}  // namespace tactus
