#pragma once
// Errors shared by every stage. User-facing failures carry where they happened (file, field)
// and what was expected, so `main` can print one clear line and exit non-zero.
#include <stdexcept>
#include <string>

namespace tactus {

// Base of every error tactus reports to a user.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Bad input: a missing or corrupt file, a wrong size, an unknown or out-of-range parameter.
class InputError : public Error {
 public:
  // file: the path (or "command line"); field: the dataset, key or option; expected: what a
  // valid value looks like; found: what was there instead (optional).
  InputError(std::string file, std::string field, std::string expected, std::string found = {});
  // An already composed message (one that crossed a process boundary).
  struct Formatted {};
  InputError(Formatted, std::string file, std::string field, const std::string& message);
  const std::string& file() const noexcept { return file_; }
  const std::string& field() const noexcept { return field_; }

 private:
  std::string file_, field_;
};

// An output that cannot be written: no permission, no space, a path under a file, a refusal to
// replace something tactus did not write. `path` names where.
class WriteError : public Error {
 public:
  WriteError(std::string path, std::string reason);
  const std::string& path() const noexcept { return path_; }

 private:
  std::string path_;
};

// A run that finished but whose figures differ from a stored reference beyond tolerance.
class CheckFailed : public Error {
 public:
  using Error::Error;
};

// A physics or numerical failure during a run: NaN, an inverted element, energy blow-up.
class NumericalError : public Error {
 public:
  using Error::Error;
};

}  // namespace tactus
