#include "tactus/core/error.hpp"

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

}  // namespace tactus
