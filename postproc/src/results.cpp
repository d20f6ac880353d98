// Reading a results folder: results.pvd (ParaView collection), history.csv, run.json.
#include "tactus/postproc/results.hpp"

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "tactus/core/error.hpp"

namespace fs = std::filesystem;

namespace tactus::postproc {

const std::vector<double>& History::column(const std::string& name) const {
  auto it = columns.find(name);
  if (it == columns.end()) throw InputError("history.csv", name, "a column named " + name, "none");
  return it->second;
}

History read_history_csv(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), "", "a readable history.csv (written by tactus-solve)", "no such file");
  History h;
  std::string line;
  if (!std::getline(in, line) || line.empty()) throw InputError(file.string(), "line 1", "a header row", "empty file");
  std::stringstream hs(line);
  for (std::string name; std::getline(hs, name, ',');) h.names.push_back(name), h.columns[name];
  std::size_t row = 1;
  while (std::getline(in, line)) {
    ++row;
    if (line.empty()) continue;
    std::stringstream ls(line);
    std::size_t k = 0;
    for (std::string cell; std::getline(ls, cell, ','); ++k) {
      if (k >= h.names.size()) break;
      char* end = nullptr;
      const double v = std::strtod(cell.c_str(), &end);
      if (end == cell.c_str()) throw InputError(file.string(), "line " + std::to_string(row), "numbers", "\"" + cell + "\"");
      h.columns[h.names[k]].push_back(v);
    }
    if (k != h.names.size())
      throw InputError(file.string(), "line " + std::to_string(row), std::to_string(h.names.size()) + " values",
                       std::to_string(k) + " (truncated file?)");
  }
  return h;
}

Results read_results(const fs::path& folder) {
  Results r;
  r.folder = fs::absolute(folder);
  if (!fs::is_directory(folder)) throw InputError(folder.string(), "", "a results folder written by tactus-solve", "no such folder");
  const fs::path pvd = folder / "results.pvd";
  std::ifstream in(pvd);
  if (!in) throw InputError(pvd.string(), "", "the results listing results.pvd", "no such file");
  std::stringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  const std::regex dataset(R"re(<DataSet\s+timestep="([^"]+)"[^>]*file="([^"]+)")re");
  for (auto it = std::sregex_iterator(s.begin(), s.end(), dataset); it != std::sregex_iterator(); ++it) {
    Frame f;
    try {
      f.time = std::stod((*it)[1].str());
    } catch (...) {
      throw InputError(pvd.string(), "DataSet timestep", "a number", (*it)[1].str());
    }
    f.file = r.folder / (*it)[2].str();
    if (!fs::exists(f.file))
      throw InputError(pvd.string(), "DataSet file", "an existing state file", f.file.string() + " is missing");
    r.frames.push_back(f);
  }
  if (s.find("<Collection") == std::string::npos) throw InputError(pvd.string(), "", "a VTK Collection file", "other content");
  std::stable_sort(r.frames.begin(), r.frames.end(), [](const Frame& a, const Frame& b) { return a.time < b.time; });
  r.history = read_history_csv(folder / "history.csv");
  std::ifstream rj(folder / "run.json");
  if (!rj) throw InputError((folder / "run.json").string(), "", "run.json written by tactus-solve", "no such file");
  std::stringstream rjs;
  rjs << rj.rdbuf();
  r.run_json = rjs.str();
  try {
    const auto j = nlohmann::json::parse(r.run_json);
    if (j.contains("materials")) r.materials = j["materials"].get<std::vector<std::string>>();
    if (j.contains("bodies")) r.bodies = j["bodies"].get<std::vector<std::string>>();
  } catch (const nlohmann::json::exception& e) {
    throw InputError((folder / "run.json").string(), "", "valid JSON", e.what());
  }
  return r;
}

}  // namespace tactus::postproc
