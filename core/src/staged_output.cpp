#include "tactus/core/staged_output.hpp"

#include <unistd.h>

#include "tactus/core/error.hpp"

namespace fs = std::filesystem;

namespace tactus {

void ensure_parent_directory(const fs::path& path) {
  const fs::path parent = path.parent_path();
  if (parent.empty()) return;
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) throw InputError(parent.string(), "", "a directory that can be created", ec.message());
}

StagedOutput::StagedOutput(fs::path final_path) : final_(std::move(final_path)) {
  ensure_parent_directory(final_);
  staging_ = final_;
  staging_ += ".partial-" + std::to_string(getpid());
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

StagedOutput::~StagedOutput() {
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

void StagedOutput::commit() {
  std::error_code ec;
  if (!fs::exists(staging_, ec))
    throw InputError(staging_.string(), "", "a staged output to commit", "nothing written");
  if (fs::is_directory(final_, ec)) fs::remove_all(final_, ec);
  fs::rename(staging_, final_, ec);
  if (ec) throw InputError(final_.string(), "", "a writable output location", ec.message());
  committed_ = true;
}

}  // namespace tactus
