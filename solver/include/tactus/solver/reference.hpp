#pragma once
// Regression references: the figures of a run (energies, contact peaks, per-material peak von
// Mises, steps, time-step range) stored with tolerances, and compared with a new run's run.json
// by `tactus-solve --check REF.json`. Every change that moves these numbers for the bundled
// cases updates its reference in the same commit and says why (bench/references/).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace tactus::solver {

struct FigureCheck {
  std::string name;
  double reference = 0, value = 0;
  double allowed = 0;  // |value - reference| allowed
  bool present = true, ok = true;
};

// The figures of a run.json, flat: "energy.kinetic", "contact.peak_force", "peak_von_mises.bone", ...
std::vector<std::pair<std::string, double>> reference_figures(const nlohmann::json& run_json);

// A reference from a run: every figure with its default tolerance (energies, forces, areas and
// step counts 1e-6 relative; peaks of pressure and stress 1 %; energies relative to the largest
// energy of the run, so a balance error near zero is judged against the energy it balances).
nlohmann::json make_reference(const nlohmann::json& run_json, const std::string& case_name);

// Compares; a figure missing from either side fails. Throws InputError on a malformed reference.
std::vector<FigureCheck> check_reference(const nlohmann::json& run_json, const nlohmann::json& reference, const std::string& file);

// The comparison as a table, one line per figure.
std::string format_checks(const std::vector<FigureCheck>& checks);

}  // namespace tactus::solver
