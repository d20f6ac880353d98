// tactus-solve: explicit dynamic simulation of a scenario.toml. Thin driver over tactus::solver.
#include <cmath>
#include <fstream>
#include <iostream>
#include <optional>

#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/output.hpp"

#include "tactus/core/cli.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/staged_output.hpp"
#include "tactus/solver/checkpoint.hpp"
#include "tactus/solver/reference.hpp"
#include "tactus/solver/run.hpp"
#include "tactus/solver/scenario.hpp"

int main(int argc, char** argv) {
  using namespace tactus;
  CLI::App app{"tactus-solve: explicit total-Lagrangian dynamics (HGO soft tissue, elastic bone) of a scenario.toml", "tactus-solve"};
  cli::CommonOptions common;
  cli::add_common_options(app, common, "output folder for results (default: results next to the scenario)");
  std::string scenario_file;
  app.add_option("scenario", scenario_file, "scenario.toml")->check(CLI::ExistingFile);
  std::string restart_dir;
  app.add_option("--restart", restart_dir,
                 "continue the killed or interrupted run that was writing this output folder from its newest checkpoint "
                 "(run.checkpoint_interval); its scenario, meshes and end time are the ones it was started with");
  bool resume = false;
  app.add_flag("--resume", resume,
               "continue a killed run of this same scenario into -o from its newest checkpoint when there is one "
               "(inputs unchanged), else start from t = 0 (what tactus-pipeline does)");
  std::string mesh_dir;
  app.add_option("--meshes", mesh_dir,
                 "folder that relative mesh and fibre paths of the scenario start from "
                 "(default: the scenario's folder)")
      ->check(CLI::ExistingDirectory);
  double end_time = 0;
  auto* end_time_opt = app.add_option("--end-time", end_time,
                                      "stop at this time (s) instead of the scenario's run.end_time; later "
                                      "output times are dropped");
  std::string check_file, write_reference;
  app.add_option("--check", check_file,
                 "compare the run's figures with a stored reference (JSON) and print each difference; "
                 "exit 5 when one is beyond its tolerance")
      ->check(CLI::ExistingFile);
  app.add_option("--write-reference", write_reference,
                 "write the run's figures as a reference with default tolerances "
                 "(replaces only an existing tactus reference)");
  app.require_subcommand(0, 1);

  auto* keys = app.add_subcommand("keys", "print the reference of every scenario key (Markdown)");
  auto* results_ref = app.add_subcommand("results-reference", "print the reference of the result files (Markdown, or --json)");
  bool results_json = false;
  results_ref->add_flag("--json", results_json, "as JSON (what the Python tools read)");
  auto* plan =
      app.add_subcommand("mesh-plan", "print the scenario's [[pipeline.meshes]] and the files its bodies read, as JSON (what tactus-pipeline runs)");
  std::string plan_scenario, plan_meshes;
  plan->add_option("scenario", plan_scenario, "scenario.toml")->required();
  plan->add_option("--meshes", plan_meshes, "the folder the mesh and fibre paths are relative to (default: the scenario's)");
  auto* mtest = app.add_subcommand("material-point", "Cauchy stress vs stretch of one material of a scenario, as CSV");
  mtest->alias("material-test");
  std::string mt_scenario, mt_material, mt_mode = "uniaxial", mt_output;
  double mt_max = 1.3;
  int mt_samples = 30;
  mtest->add_option("scenario", mt_scenario, "scenario.toml")->required()->check(CLI::ExistingFile);
  mtest->add_option("--material", mt_material, "material name in the scenario")->required();
  mtest->add_option("--mode", mt_mode, "uniaxial | equibiaxial | shear")->capture_default_str();
  mtest->add_option("--max", mt_max, "largest stretch (or shear gamma)")->capture_default_str();
  mtest->add_option("--samples", mt_samples, "number of increments")->capture_default_str();
  mtest->add_option("-o,--output", mt_output, "CSV file (default: standard output)");

  return cli::run(app, argc, argv, common, [&] {
    if (keys->parsed()) {
      std::cout << solver::scenario_reference_markdown();
      return;
    }
    if (results_ref->parsed()) {
      std::cout << (results_json ? solver::results_reference_json().dump(2) + "\n" : solver::results_reference_markdown());
      return;
    }
    if (plan->parsed()) {
      std::cout << solver::mesh_plan_json(solver::read_scenario(plan_scenario, plan_meshes));
      return;
    }
    if (mtest->parsed()) {
      const std::string csv = solver::material_point_csv(solver::read_scenario(mt_scenario), mt_material, mt_mode, mt_max, mt_samples);
      if (mt_output.empty()) {
        std::cout << csv;
      } else {
        OutputFiles out({mt_output}, common.output_rules({mt_scenario}));
        write_file(out.staged(0), csv);
        out.commit();
      }
      return;
    }
    solver::SolveRequest request{scenario_file, mesh_dir, common.output, restart_dir, std::nullopt, resume};
    if (*end_time_opt) request.end_time = end_time;
    if (restart_dir.empty() && scenario_file.empty()) throw CLI::RequiredError("scenario");
    solver::PreparedRun run = solver::prepare_run(request);
    const solver::Scenario& sc = run.scenario;
    scenario_file = run.scenario_file.string();
    // The reference is read before the run: a malformed one is refused up front.
    nlohmann::json reference;
    if (!check_file.empty()) {
      require_regular_file(check_file, "a reference (JSON)");
      std::ifstream in(check_file);
      reference = nlohmann::json::parse(in, nullptr, false);
      solver::check_reference(nlohmann::json::object(), reference, check_file);
    }
    // A reference replaces only a reference tactus wrote there (its manifest says so), checked before the run.
    std::optional<OutputFiles> reference_out;
    if (!write_reference.empty()) reference_out.emplace(std::vector<std::filesystem::path>{write_reference}, common.output_rules({scenario_file}));
    OutputFolder output(run.output, common.output_rules(solver::scenario_inputs(sc)), run.from ? run.from->staging : std::filesystem::path());
    const solver::RunSummary summary = solver::run_simulation(sc, output, run.identity, run.from ? &*run.from : nullptr);
    if (reference_out) {
      write_file(reference_out->staged(0),
                 solver::make_reference(summary.run_json, std::filesystem::path(scenario_file).stem().string()).dump(2) + '\n');
      reference_out->commit();
      log::info() << "reference written: " << write_reference;
    }
    if (!check_file.empty()) {
      const auto checks = solver::check_reference(summary.run_json, reference, check_file);
      std::cout << "reference " << check_file << ":\n" << solver::format_checks(checks);
      std::string failed;
      for (const auto& c : checks)
        if (!c.ok) failed += (failed.empty() ? "" : ", ") + c.name;
      if (!failed.empty()) throw CheckFailed(check_file + ": beyond tolerance: " + failed);
      log::info() << "all " << checks.size() << " figures within their tolerances of " << check_file;
    }
  });
}
