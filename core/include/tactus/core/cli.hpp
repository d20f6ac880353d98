#pragma once
// The command-line convention shared by every tactus executable: --help, --version,
// -o/--output, --force, -v/--verbose (repeatable), -q/--quiet; errors reported as one line
// "<program>: error: <what>" with a non-zero exit (1 bad input or an output that cannot be
// written, 2 usage, 3 numerical failure, 4 internal error, 5 a reference check failed,
// 128 + signal when interrupted).
#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "tactus/core/output.hpp"

namespace tactus::cli {

struct CommonOptions {
  std::string output;
  int verbose = 0;
  bool quiet = false;
  bool force = false;
  std::string output_required;  // non-empty: -o must be given; says what it names
  std::string program;          // the executable's name, set by run()

  // The output rules of this tool for the given inputs (output.hpp).
  OutputRules output_rules(std::vector<std::filesystem::path> inputs) const;
};

// Adds --version, -v, -q, and (when output_help is non-empty) -o/--output and --force to `app`.
// With `required_output` (e.g. "an output folder"), `run` stops with an input error when -o is
// missing.
void add_common_options(CLI::App& app, CommonOptions& options, const std::string& output_help, const std::string& required_output = {});

// Installs the interrupt handling, parses, applies the log level, runs `body` and turns every
// tactus error into one message and exit code.
int run(CLI::App& app, int argc, char** argv, CommonOptions& options, const std::function<void()>& body);

}  // namespace tactus::cli
