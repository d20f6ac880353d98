#include "tactus/core/error.hpp"

#include <cerrno>
#include <cstring>

namespace tactus {

namespace {
std::string compose(const std::string& file, const std::string& field, const std::string& expected, const std::string& found) {
  std::string msg = file;
  if (!field.empty()) msg += ": " + field;
  msg += ": expected " + expected;
  if (!found.empty()) msg += ", found " + found;
  return msg;
}
}  // namespace

InputError::InputError(std::string file, std::string field, std::string expected, std::string found)
    : Error(compose(file, field, expected, found)), file_(std::move(file)), field_(std::move(field)) {}

InputError::InputError(Formatted, std::string file, std::string field, const std::string& message)
    : Error(message), file_(std::move(file)), field_(std::move(field)) {}

WriteError::WriteError(std::string path, std::string reason) : Error(path + ": cannot write: " + reason), path_(std::move(path)) {}

namespace {
bool is_no_space(int err) { return err == ENOSPC || err == EDQUOT; }
std::string system_reason(const std::string& doing, int err) {
  if (is_no_space(err)) return doing + ": no space left on device" + (err == EDQUOT ? " (disk quota exceeded)" : "");
  return doing + ": " + std::strerror(err);
}
}  // namespace

WriteError::WriteError(Composed, std::string message, std::string path, bool no_space)
    : Error(std::move(message)), path_(std::move(path)), no_space_(no_space) {}

WriteError WriteError::with_note(const std::string& note) const { return WriteError(Composed{}, std::string(what()) + note, path_, no_space_); }

WriteError::WriteError(std::string path, const std::string& doing, int err)
    : Error(path + ": cannot write: " + system_reason(doing, err)), path_(std::move(path)), no_space_(is_no_space(err)) {}

}  // namespace tactus
