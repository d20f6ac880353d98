#include "tactus/core/cli.hpp"

#include <cctype>
#include <iostream>
#include <new>

#include "tactus/core/error.hpp"
#include "tactus/core/interrupt.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/version.hpp"

namespace tactus::cli {

OutputRules CommonOptions::output_rules(std::vector<std::filesystem::path> inputs) const { return {program, std::move(inputs), force}; }

void add_common_options(CLI::App& app, CommonOptions& options, const std::string& output_help, const std::string& required_output) {
  options.output_required = required_output;
  app.set_version_flag("--version", std::string("tactus ") + kVersion);
  app.add_flag("-v,--verbose", options.verbose, "More detail in the log (repeat for debug)");
  app.add_flag("-q,--quiet", options.quiet, "Only errors");
  if (!output_help.empty()) {
    app.add_option("-o,--output", options.output, output_help);
    app.add_flag("--force", options.force,
                 "also replace a previous output of another tactus tool (a folder or file tactus did not write is "
                 "never replaced)");
  }
}

namespace {

// Every floating-point option's values, refused when not finite: "nan" and "inf" parse as
// numbers, then compare false against every bound (--angle nan ran, meaning nothing).
void require_finite_numbers(const CLI::App& app) {
  for (const CLI::Option* opt : app.get_options()) {
    if (opt->get_type_name().find("FLOAT") == std::string::npos) continue;
    for (const std::string& value : opt->results()) {
      std::size_t i = value.find_first_not_of("+- ");
      std::string word = i == std::string::npos ? "" : value.substr(i, 3);
      for (char& c : word) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      if (word == "nan" || word == "inf") throw InputError("command line", opt->get_name(), "a finite number", "'" + value + "'");
    }
  }
  for (const CLI::App* sub : app.get_subcommands()) require_finite_numbers(*sub);
}

}  // namespace

int run(CLI::App& app, int argc, char** argv, CommonOptions& options, const std::function<void()>& body) {
  const std::string program = app.get_name();
  options.program = program;
  install_interrupt_handling(program);
  // Usage errors exit with 2 (CLI11's own codes are >100); --help and --version with 0.
  auto usage = [&](const CLI::ParseError& e) { return app.exit(e) == 0 ? 0 : 2; };
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return usage(e);
  }
  log::set_level(options.quiet          ? log::Level::quiet
                 : options.verbose >= 2 ? log::Level::debug
                 : options.verbose == 1 ? log::Level::verbose
                                        : log::Level::info);
  try {
    require_finite_numbers(app);
    if (!options.output_required.empty() && options.output.empty()) throw InputError("command line", "-o/--output", options.output_required);
    body();
    return 0;
  } catch (const CLI::ParseError& e) {
    return usage(e);
  } catch (const Interrupted& e) {
    mark_interrupt_handled();
    std::cerr << program << ": " << e.what() << '\n';
    return e.exit_code();
  } catch (const CheckFailed& e) {
    std::cerr << program << ": check failed: " << e.what() << '\n';
    return 5;
  } catch (const NumericalError& e) {
    std::cerr << program << ": numerical failure: " << e.what() << '\n';
    return 3;
  } catch (const Error& e) {
    std::cerr << program << ": error: " << e.what() << '\n';
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {
    std::cerr << program << ": error: " << e.path1().string() << ": " << e.code().message() << '\n';
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << program << ": error: out of memory (the input asks for more than this machine has)\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << program << ": internal error: " << e.what() << '\n';
    return 4;
  } catch (const std::string& e) {  // (gmsh's API throws strings)
    std::cerr << program << ": internal error: " << e << '\n';
    return 4;
  } catch (...) {
    std::cerr << program << ": internal error: an unknown exception\n";
    return 4;
  }
}

}  // namespace tactus::cli
