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
  // A failed system call: `err` (errno) names the reason; ENOSPC and EDQUOT say "no space left on
  // device" and mark the error as no_space(), which a run that can be continued reacts to.
  WriteError(std::string path, const std::string& doing, int err);
  const std::string& path() const noexcept { return path_; }
  bool no_space() const noexcept { return no_space_; }
  // The same error with `note` appended to its message (what was kept, how to go on).
  WriteError with_note(const std::string& note) const;

 private:
  struct Composed {};
  WriteError(Composed, std::string message, std::string path, bool no_space);
  std::string path_;
  bool no_space_ = false;
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
