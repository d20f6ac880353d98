#pragma once
// The command-line convention shared by every tactus executable: --help, --version,
// -o/--output, -v/--verbose (repeatable), -q/--quiet; errors reported as one line
// "<program>: error: <what>" with a non-zero exit (1 bad input, 2 usage, 3 numerical failure).
#include <CLI/CLI.hpp>
#include <functional>
#include <string>

namespace tactus::cli {

struct CommonOptions {
  std::string output;
  int verbose = 0;
  bool quiet = false;
};

// Adds --version, -v, -q, and (when output_help is non-empty) -o/--output to `app`.
void add_common_options(CLI::App& app, CommonOptions& options, const std::string& output_help);

// Parses, applies the log level, runs `body` and turns every tactus error into one message.
int run(CLI::App& app, int argc, char** argv, CommonOptions& options, const std::function<void()>& body);

}  // namespace tactus::cli
