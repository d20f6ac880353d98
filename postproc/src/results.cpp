// Reading a results folder: results.pvd (ParaView collection), history.csv, run.json.
#include "tactus/postproc/results.hpp"
#include "tactus/core/file_io.hpp"

#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "state_files.hpp"
#include "tactus/core/contracts.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/vec3.hpp"

namespace fs = std::filesystem;

namespace tactus::postproc {

namespace rk = contracts::run_json;
namespace hc = contracts::history;
namespace cc = contracts::cell;
namespace cp = contracts::point;

vtkSmartPointer<vtkUnstructuredGrid> load_state(const fs::path& file) {
  require_regular_file(file, "a tactus-solve state (.vtu)");
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(file.string().c_str());
  reader->Update();
  vtkSmartPointer<vtkUnstructuredGrid> g = reader->GetOutput();
  if (!g || g->GetNumberOfCells() == 0) throw InputError(file.string(), "", "a tactus-solve state (.vtu)", "no cells");
  return g;
}

std::string ms(double t) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(2) << t * 1e3;
  return o.str();
}

std::vector<double> nodal_von_mises(vtkUnstructuredGrid* g) {
  vtkDataArray* vm = g->GetCellData()->GetArray(cc::von_mises.name);
  if (!vm) return {};
  std::vector<double> sum(static_cast<std::size_t>(g->GetNumberOfPoints()), 0.0), weight(sum.size(), 0.0);
  for (vtkIdType c = 0; c < g->GetNumberOfCells(); ++c) {
    vtkIdType n = 0;
    const vtkIdType* p = nullptr;
    g->GetCellPoints(c, n, p);
    if (n != 4) continue;
    Vec3 x[4];
    for (int a = 0; a < 4; ++a) g->GetPoint(p[a], x[a].data());
    const double volume = std::abs(dot(cross(x[1] - x[0], x[2] - x[0]), x[3] - x[0])) / 6, value = vm->GetComponent(c, 0);
    for (int a = 0; a < 4; ++a) sum[static_cast<std::size_t>(p[a])] += volume * value, weight[static_cast<std::size_t>(p[a])] += volume;
  }
  for (std::size_t i = 0; i < sum.size(); ++i) sum[i] = weight[i] > 0 ? sum[i] / weight[i] : 0.0;
  return sum;
}

const std::vector<double>& History::column(const std::string& name) const {
  auto it = columns.find(name);
  if (it == columns.end()) throw InputError("history.csv", name, "a column named " + name, "none");
  return it->second;
}

History read_history_csv(const fs::path& file) {
  require_regular_file(file, "a history.csv written by tactus-solve");
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), "", "a readable history.csv (written by tactus-solve)", "no such file");
  History h;
  std::string line;
  if (!std::getline(in, line) || line.empty()) throw InputError(file.string(), "line 1", "a header row", "empty file");
  std::stringstream hs(line);
  for (std::string name; std::getline(hs, name, ',');) h.names.push_back(name), h.columns[name];
  if (std::find(h.names.begin(), h.names.end(), contracts::history::time.name) == h.names.end())
    throw InputError(file.string(), "line 1",
                     std::string("a header row naming the columns, '") + contracts::history::time.name + "' among them (written by tactus-solve)",
                     "'" + line.substr(0, 60) + "' (no header?)");
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

void validate_run_json(const nlohmann::json& j, const std::string& file) {
  // Every key the report uses, with its type: a wrong type is named, never an internal error.
  auto require = [&](const nlohmann::json& node, const std::string& path, const char* key, const char* what, auto is) {
    if (!node.contains(key) || !is(node[key]))
      throw InputError(file, path + key, what, node.contains(key) ? node[key].dump().substr(0, 60) : "missing");
  };
  const auto number = [](const nlohmann::json& v) { return v.is_number(); };
  const auto count = [](const nlohmann::json& v) { return v.is_number_unsigned() || (v.is_number_integer() && v.get<long long>() >= 0); };
  const auto string = [](const nlohmann::json& v) { return v.is_string(); };
  const auto names = [](const nlohmann::json& v) {
    return v.is_array() && std::all_of(v.begin(), v.end(), [](const nlohmann::json& x) { return x.is_string(); });
  };
  const auto object = [](const nlohmann::json& v) { return v.is_object(); };
  require(j, "", rk::status, "a string", string);
  require(j, "", rk::materials, "an array of material names", names);
  require(j, "", rk::bodies, "an array of body names", names);
  for (const char* k : {rk::steps, rk::nodes, rk::tets}) require(j, "", k, "a count (integer >= 0)", count);
  for (const char* k : {rk::end_time, rk::wall_time}) require(j, "", k, "a number", number);
  require(j, "", rk::time_step, "an object", object);
  // A run that failed before its first step has no step sizes nor energies yet (null).
  const bool completed = j[rk::status] == "completed";
  const auto measured = [&](const nlohmann::json& v) { return v.is_number() || (!completed && v.is_null()); };
  const char* measured_what = completed ? "a number" : "a number (or null: the run failed before it was measured)";
  for (const char* k : {"min", "max"}) require(j[rk::time_step], "time_step.", k, measured_what, measured);
  require(j, "", rk::energy, "an object", object);
  for (const char* k : {"initial", "balance_error", "contact_work_normal", "contact_work_friction"})
    require(j[rk::energy], "energy.", k, measured_what, measured);
  if (j.contains(rk::timing)) {
    require(j, "", rk::timing, "an object", object);
    for (const char* k : {"stress_passes", "contact"}) require(j[rk::timing], "timing_s.", k, "a number", number);
  }
  if (j.contains(rk::message) && !j[rk::message].is_null() && !j[rk::message].is_string())
    throw InputError(file, rk::message, "a string or null", j[rk::message].dump().substr(0, 60));
  if (j.contains(rk::contact)) {
    const auto& c = j[rk::contact];
    require(j, "", rk::contact, "an object", object);
    require(c, "contact.", "steps_in_contact", "a count", count);
    for (const char* k : {"peak_force", "peak_area", "peak_pressure"}) {
      require(c, "contact.", k, "an object", object);
      for (const char* v : {"value", "time"}) require(c[k], std::string("contact.") + k + ".", v, "a number", number);
    }
    const auto& p = c["peak_pressure"];
    if (p.contains("position"))
      require(p, "contact.peak_pressure.", "position", "[x, y, z]", [](const nlohmann::json& v) {
        return v.is_array() && v.size() == 3 && std::all_of(v.begin(), v.end(), [](const nlohmann::json& x) { return x.is_number(); });
      });
    if (p.contains("node") && !p["node"].is_null() && !p["node"].is_number_integer())
      throw InputError(file, "contact.peak_pressure.node", "a node number or null", p["node"].dump().substr(0, 60));
  }
}

Results read_results(const fs::path& folder) {
  Results r;
  r.folder = fs::absolute(folder);
  if (!fs::is_directory(folder)) throw InputError(folder.string(), "", "a results folder written by tactus-solve", "no such folder");
  const fs::path pvd = folder / "results.pvd";
  require_regular_file(pvd, "the results listing results.pvd");
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
    // A state file gone (deleted, a disk that filled): the report says so and shows the others.
    if (!fs::exists(f.file)) {
      std::ostringstream what;
      what << (*it)[2].str() << " (t = " << f.time << " s) is missing";
      r.missing.push_back(what.str());
      log::warn(pvd.string() + ": " + what.str() + "; the report leaves it out");
      continue;
    }
    r.frames.push_back(f);
  }
  if (s.find("<Collection") == std::string::npos) throw InputError(pvd.string(), "", "a VTK Collection file", "other content");
  std::stable_sort(r.frames.begin(), r.frames.end(), [](const Frame& a, const Frame& b) { return a.time < b.time; });
  r.history = read_history_csv(folder / "history.csv");
  require_regular_file(folder / "run.json", "run.json written by tactus-solve");
  std::ifstream rj(folder / "run.json");
  if (!rj) throw InputError((folder / "run.json").string(), "", "run.json written by tactus-solve", "no such file");
  std::stringstream rjs;
  rjs << rj.rdbuf();
  r.run_json = rjs.str();
  const std::string rj_file = (folder / "run.json").string();
  const auto j = nlohmann::json::parse(r.run_json, nullptr, false);
  if (j.is_discarded() || !j.is_object()) throw InputError(rj_file, "", "a JSON object (run.json written by tactus-solve)", "malformed JSON");
  validate_run_json(j, rj_file);
  if (r.frames.empty()) {
    // A run that failed before its first output: its failure is the report.
    const std::string status = j[rk::status].get<std::string>();
    const std::string message = j.contains(rk::message) && j[rk::message].is_string() ? j[rk::message].get<std::string>() : "";
    if (status != "completed")
      throw InputError(rj_file, rk::status, "a run with at least one output state to report on",
                       "a run that " + status + " at step " + std::to_string(j[rk::steps].get<long long>()) + " before writing any" +
                           (message.empty() ? std::string() : ": " + message));
    throw InputError(pvd.string(), "DataSet", "at least one output state to report on",
                     r.missing.empty() ? "none (the run wrote no state: see run.json)" : "every state file is missing");
  }
  for (const char* key : {rk::materials, rk::bodies}) {
    auto& names = std::string(key) == rk::materials ? r.materials : r.bodies;
    for (const auto& n : j[key]) names.push_back(n.get<std::string>());
  }
  return r;
}

}  // namespace tactus::postproc
