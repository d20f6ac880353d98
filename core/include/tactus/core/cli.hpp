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
  std::string output_required;  // non-empty: -o must be given; says what it names
};

// Adds --version, -v, -q, and (when output_help is non-empty) -o/--output to `app`. With
// `required_output` (e.g. "an output folder"), `run` stops with an input error when -o is missing.
void add_common_options(CLI::App& app, CommonOptions& options, const std::string& output_help,
                        const std::string& required_output = {});

// Parses, applies the log level, runs `body` and turns every tactus error into one message.
int run(CLI::App& app, int argc, char** argv, CommonOptions& options, const std::function<void()>& body);

}  // namespace tactus::cli
