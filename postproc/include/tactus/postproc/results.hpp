#pragma once
// A solver results folder as written by tactus-solve (solver/run.hpp): results.pvd and the
// state .vtu files it lists, history.csv and run.json. Every missing or corrupt piece is an
// InputError naming the file.
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace tactus::postproc {

struct Frame {
  double time = 0;
  std::filesystem::path file;  // absolute
};

// history.csv as columns by header name.
struct History {
  std::vector<std::string> names;
  std::map<std::string, std::vector<double>> columns;
  std::size_t rows() const { return names.empty() ? 0 : columns.at(names.front()).size(); }
  bool has(const std::string& name) const { return columns.count(name) != 0; }
  const std::vector<double>& column(const std::string& name) const;  // InputError when absent
};

struct Results {
  std::filesystem::path folder;
  std::vector<Frame> frames;  // in time order
  History history;
  std::string run_json;                        // text of run.json (parsed where needed)
  std::vector<std::string> materials, bodies;  // names behind the "material" / "body" cell fields
  std::vector<std::string> missing;            // states results.pvd lists whose files are gone (left out, said)
};

// Reads the listing and history, checks which state files exist (the states themselves are
// read when needed). Throws InputError on a missing results.pvd, history.csv, run.json or state.
Results read_results(const std::filesystem::path& folder);

History read_history_csv(const std::filesystem::path& file);

// Checks every run.json key the report uses, with its type (InputError naming the key).
void validate_run_json(const nlohmann::json& run_json, const std::string& file);

}  // namespace tactus::postproc
