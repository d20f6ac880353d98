#include "tactus/core/staged_output.hpp"

#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"

namespace fs = std::filesystem;

namespace tactus {

void ensure_parent_directory(const fs::path& path) {
  const fs::path parent = path.parent_path();
  if (parent.empty()) return;
  std::error_code ec;
  if (fs::is_directory(parent, ec)) return;
  fs::create_directories(parent, ec);
  if (ec) throw WriteError(parent.string(), "cannot create the folder (" + ec.message() + ")");
}

StagedOutput::StagedOutput(fs::path final_path) : final_(std::move(final_path)) {
  ensure_parent_directory(final_);
  staging_ = final_;
  staging_ += ".partial-" + unique_suffix();
}

StagedOutput::~StagedOutput() {
  if (committed_) return;
  std::error_code ec;
  fs::remove(staging_, ec);
}

void StagedOutput::commit(std::string_view tail, const std::string& format) {
  std::error_code ec;
  if (!fs::is_regular_file(staging_, ec)) throw WriteError(final_.string(), "nothing was written (the file system refused it?)");
  if (fs::is_directory(final_, ec)) throw WriteError(final_.string(), "a folder is there; a file cannot replace it");
  if (!tail.empty()) require_tail(staging_, tail, format);
  sync_file(staging_);
  fs::rename(staging_, final_, ec);
  if (ec) throw WriteError(final_.string(), "cannot move the file into place", ec.value());
  committed_ = true;
  sync_directory(final_.parent_path());
}

}  // namespace tactus
