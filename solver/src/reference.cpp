#include "tactus/solver/reference.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "tactus/core/error.hpp"

namespace tactus::solver {

namespace {

using nlohmann::json;

double number_at(const json& j, std::initializer_list<const char*> path) {
  const json* node = &j;
  for (const char* key : path) {
    if (!node->is_object() || !node->contains(key)) return std::nan("");
    node = &(*node)[key];
  }
  return node->is_number() ? node->get<double>() : std::nan("");
}

// The scale a figure's tolerance is relative to.
double energy_scale(const json& run) {
  double s = 0;
  for (const char* k : {"initial", "kinetic", "internal", "external_work", "damping_work"}) {
    const double v = number_at(run, {"energy", k});
    if (std::isfinite(v)) s = std::max(s, std::abs(v));
  }
  return s;
}

}  // namespace

std::vector<std::pair<std::string, double>> reference_figures(const json& run) {
  std::vector<std::pair<std::string, double>> f;
  for (const char* k : {"kinetic", "internal", "external_work", "damping_work", "contact_work_normal", "contact_work_friction", "balance_error"})
    f.emplace_back(std::string("energy.") + k, number_at(run, {"energy", k}));
  if (run.contains("contact")) {
    f.emplace_back("contact.peak_force", number_at(run, {"contact", "peak_force", "value"}));
    f.emplace_back("contact.peak_area", number_at(run, {"contact", "peak_area", "value"}));
    f.emplace_back("contact.peak_pressure", number_at(run, {"contact", "peak_pressure", "value"}));
  }
  if (run.contains("peak_von_mises_at_outputs") && run["peak_von_mises_at_outputs"].is_object())
    for (const auto& [name, v] : run["peak_von_mises_at_outputs"].items())
      f.emplace_back("peak_von_mises." + name, v.is_number() ? v.get<double>() : std::nan(""));
  f.emplace_back("steps", number_at(run, {"steps"}));
  f.emplace_back("outputs", number_at(run, {"outputs"}));
  f.emplace_back("end_time", number_at(run, {"end_time"}));
  f.emplace_back("time_step.min", number_at(run, {"time_step", "min"}));
  f.emplace_back("time_step.max", number_at(run, {"time_step", "max"}));
  return f;
}

json make_reference(const json& run, const std::string& case_name) {
  json figures = json::object();
  const double escale = energy_scale(run);
  for (const auto& [name, value] : reference_figures(run)) {
    const bool peak = name.rfind("peak_von_mises.", 0) == 0 || name == "contact.peak_pressure";
    json fig = {{"value", value}, {"tolerance", peak ? 0.01 : 1e-6}};
    if (name.rfind("energy.", 0) == 0) fig["relative_to"] = escale;  // else relative to |value|
    figures[name] = fig;
  }
  return {{"tactus_reference", 1},
          {"case", case_name},
          {"tactus_version", run.value("tactus_version", "")},
          {"how", "tolerance is relative to max(|value|, relative_to); update with tactus-solve --write-reference"},
          {"figures", figures}};
}

std::vector<FigureCheck> check_reference(const json& run, const json& ref, const std::string& file) {
  if (!ref.is_object() || !ref.contains("tactus_reference") || !ref.contains("figures") || !ref["figures"].is_object())
    throw InputError(file, "", "a tactus reference (written by tactus-solve --write-reference)", "another file");
  std::vector<FigureCheck> out;
  const auto now = reference_figures(run);
  for (const auto& [name, fig] : ref["figures"].items()) {
    if (!fig.is_object() || !fig.contains("value") || !fig.contains("tolerance") || !fig["tolerance"].is_number() ||
        (!fig["value"].is_number() && !fig["value"].is_null()))
      throw InputError(file, "figures." + name, "{\"value\": number, \"tolerance\": number}", fig.dump().substr(0, 80));
    FigureCheck c;
    c.name = name;
    c.reference = fig["value"].is_number() ? fig["value"].get<double>() : std::nan("");
    const double scale = std::max(std::abs(c.reference), fig.value("relative_to", 0.0));
    c.allowed = fig["tolerance"].get<double>() * scale;
    auto it = std::find_if(now.begin(), now.end(), [&](const auto& p) { return p.first == name; });
    c.present = it != now.end();
    c.value = c.present ? it->second : std::nan("");
    c.ok = c.present && ((std::isnan(c.value) && std::isnan(c.reference)) || std::abs(c.value - c.reference) <= c.allowed);
    out.push_back(c);
  }
  for (const auto& [name, value] : now)
    if (!ref["figures"].contains(name)) out.push_back({name, std::nan(""), value, 0, false, false});
  return out;
}

std::string format_checks(const std::vector<FigureCheck>& checks) {
  std::string s;
  char line[256];
  std::snprintf(line, sizeof line, "%-34s %16s %16s %12s %12s  %s\n", "figure", "reference", "this run", "difference", "allowed", "");
  s += line;
  for (const auto& c : checks) {
    std::snprintf(line, sizeof line, "%-34s %16.9g %16.9g %12.3g %12.3g  %s\n", c.name.c_str(), c.reference, c.value, c.value - c.reference,
                  c.allowed, c.ok ? "ok" : (c.present ? "FAIL" : "FAIL (missing)"));
    s += line;
  }
  return s;
}

}  // namespace tactus::solver
