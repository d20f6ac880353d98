// tactus-solve: explicit dynamic simulation of a scenario.toml. Thin driver over tactus::solver.
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/output.hpp"

#include "tactus/core/cli.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/staged_output.hpp"
#include "tactus/solver/checkpoint.hpp"
#include "tactus/solver/decomposition.hpp"
#include "tactus/solver/model_build.hpp"
#include "tactus/solver/reference.hpp"
#include "tactus/solver/run.hpp"
#include "tactus/solver/scenario.hpp"
#ifdef TACTUS_MPI
#include "tactus/solver/ranks.hpp"
#endif

namespace {

using namespace tactus;

// The options of a run (the tool's main job).
struct SolveOptions {
  std::string scenario_file, restart_dir, mesh_dir, check_file, write_reference, partition;
  std::vector<std::string> overrides;
  bool resume = false;
  double end_time = 0;
  CLI::Option* end_time_option = nullptr;
};

void add_solve_options(CLI::App& app, SolveOptions& o) {
  app.add_option("scenario", o.scenario_file, "scenario.toml")->check(CLI::ExistingFile);
  app.add_option("--restart", o.restart_dir,
                 "continue the killed or interrupted run that was writing this output folder from its newest checkpoint "
                 "(run.checkpoint_interval); its scenario, meshes and end time are the ones it was started with");
  app.add_flag("--resume", o.resume,
               "continue a killed run of this same scenario into -o from its newest checkpoint when there is one "
               "(inputs unchanged), else start from t = 0 (what tactus-pipeline does)");
  app.add_option("--meshes", o.mesh_dir,
                 "folder that relative mesh and fibre paths of the scenario start from "
                 "(default: the scenario's folder)")
      ->check(CLI::ExistingDirectory);
  o.end_time_option = app.add_option("--end-time", o.end_time,
                                     "stop at this time (s) instead of the scenario's run.end_time; later "
                                     "output times are dropped");
  app.add_option("--set", o.overrides,
                 "KEY=VALUE: replace one scenario value (repeatable; e.g. --set grasp.target_force=30 --set pipeline.meshes.2.radius=0.015: "
                 "a dotted path, a [[...]] entry by its 0-based index); run.json lists them")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.add_option("--check", o.check_file,
                 "compare the run's figures with a stored reference (JSON) and print each difference; "
                 "exit 5 when one is beyond its tolerance")
      ->check(CLI::ExistingFile);
  app.add_option("--partition", o.partition,
                 "under mpirun: the ranks' atoms from this file (JSON: atom_tets, ranks, atom_rank; tactus-solve decompose -o writes one) "
                 "instead of METIS's cut")
      ->check(CLI::ExistingFile);
  app.add_option("--write-reference", o.write_reference,
                 "write the run's figures as a reference with default tolerances "
                 "(replaces only an existing tactus reference)");
}

// The subcommands that print a reference or evaluate one material; run() does the one parsed.
struct Tools {
  CLI::App *keys, *results_reference, *mesh_plan, *material_point, *decompose;
  bool results_json = false;
  std::string plan_scenario, plan_meshes;
  std::vector<std::string> plan_overrides;
  std::string mt_scenario, mt_material, mt_mode = "uniaxial", mt_output;
  double mt_max = 1.3;
  int mt_samples = 30;
  std::string dc_scenario, dc_meshes, dc_partition, dc_output;
  std::vector<std::string> dc_overrides;
  int dc_ranks = 2;
  std::size_t dc_atom_tets = solver::kAtomTets;

  explicit Tools(CLI::App& app)
      : keys(app.add_subcommand("keys", "print the reference of every scenario key (Markdown)")),
        results_reference(app.add_subcommand("results-reference", "print the reference of the result files (Markdown, or --json)")),
        mesh_plan(app.add_subcommand("mesh-plan",
                                     "print the scenario's [[pipeline.meshes]] and the files its bodies read, as JSON (what tactus-pipeline runs)")),
        material_point(app.add_subcommand("material-point", "Cauchy stress vs stretch of one material of a scenario, as CSV")),
        decompose(app.add_subcommand("decompose", "split the scenario's model into ranks (METIS on atoms of tets) and print the quality")) {
    results_reference->add_flag("--json", results_json, "as JSON (what the Python tools read)");
    mesh_plan->add_option("scenario", plan_scenario, "scenario.toml")->required();
    mesh_plan->add_option("--meshes", plan_meshes, "the folder the mesh and fibre paths are relative to (default: the scenario's)");
    mesh_plan->add_option("--set", plan_overrides, "KEY=VALUE: replace one scenario value, as tactus-solve --set (repeatable)")
        ->expected(1)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    material_point->alias("material-test");
    material_point->add_option("scenario", mt_scenario, "scenario.toml")->required()->check(CLI::ExistingFile);
    material_point->add_option("--material", mt_material, "material name in the scenario")->required();
    material_point->add_option("--mode", mt_mode, "uniaxial | equibiaxial | shear")->capture_default_str();
    material_point->add_option("--max", mt_max, "largest stretch (or shear gamma)")->capture_default_str();
    material_point->add_option("--samples", mt_samples, "number of increments")->capture_default_str();
    material_point->add_option("-o,--output", mt_output, "CSV file (default: standard output)");
    decompose->add_option("scenario", dc_scenario, "scenario.toml")->required()->check(CLI::ExistingFile);
    decompose->add_option("--ranks", dc_ranks, "number of ranks")->capture_default_str();
    decompose->add_option("--atom-tets", dc_atom_tets, "tets per atom (a block's last atom may be smaller)")->capture_default_str();
    decompose->add_option("--partition", dc_partition, "a partition to measure instead of METIS's (JSON: atom_tets, ranks, atom_rank)")
        ->check(CLI::ExistingFile);
    decompose->add_option("-o,--output", dc_output, "also write the decomposition as JSON (format \"tactus decomposition\")");
    decompose->add_option("--meshes", dc_meshes, "the folder the mesh and fibre paths are relative to (default: the scenario's)");
    decompose->add_option("--set", dc_overrides, "KEY=VALUE: replace one scenario value, as tactus-solve --set (repeatable)")
        ->expected(1)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  }

  // False when no subcommand was given (the run itself is wanted).
  bool run(const cli::CommonOptions& common) const {
    if (keys->parsed()) {
      std::cout << solver::scenario_reference_markdown();
    } else if (results_reference->parsed()) {
      std::cout << (results_json ? solver::results_reference_json().dump(2) + "\n" : solver::results_reference_markdown());
    } else if (mesh_plan->parsed()) {
      std::cout << solver::mesh_plan_json(solver::read_scenario(plan_scenario, plan_meshes, plan_overrides));
    } else if (decompose->parsed()) {
      if (dc_atom_tets < 1 || dc_atom_tets > 1000000)
        throw InputError("command line", "--atom-tets", "1 to 1,000,000 tets", std::to_string(dc_atom_tets));
      const solver::Model model = solver::build_model(solver::read_scenario(dc_scenario, dc_meshes, dc_overrides));
      const solver::Decomposition d =
          dc_partition.empty() ? solver::decompose(model, dc_ranks, dc_atom_tets, "--ranks") : solver::read_partition(model, dc_partition);
      std::cout << solver::format_decomposition(d);
      if (!dc_output.empty()) {
        OutputFiles out({dc_output}, common.output_rules({dc_scenario}));
        write_file(out.staged(0), solver::decomposition_json(d).dump(1) + "\n");
        out.commit();
      }
    } else if (material_point->parsed()) {
      const std::string csv = solver::material_point_csv(solver::read_scenario(mt_scenario), mt_material, mt_mode, mt_max, mt_samples);
      if (mt_output.empty()) {
        std::cout << csv;
      } else {
        OutputFiles out({mt_output}, common.output_rules({mt_scenario}));
        write_file(out.staged(0), csv);
        out.commit();
      }
    } else {
      return false;
    }
    return true;
  }
};

// A stored reference, read and checked for form before the run: a malformed one is refused up front.
nlohmann::json read_reference(const std::string& file) {
  require_regular_file(file, "a reference (JSON)");
  std::ifstream in(file);
  nlohmann::json reference = nlohmann::json::parse(in, nullptr, false);
  solver::check_reference(nlohmann::json::object(), reference, file);
  return reference;
}

// The run's figures against the reference, each printed; CheckFailed (exit 5) naming those beyond tolerance.
void check_against(const solver::RunSummary& summary, const nlohmann::json& reference, const std::string& file) {
  const auto checks = solver::check_reference(summary.run_json, reference, file);
  std::cout << "reference " << file << ":\n" << solver::format_checks(checks);
  std::string failed;
  for (const auto& c : checks)
    if (!c.ok) failed += (failed.empty() ? "" : ", ") + c.name;
  if (!failed.empty()) throw CheckFailed(file + ": beyond tolerance: " + failed);
  log::info() << "all " << checks.size() << " figures within their tolerances of " << file;
}

// ranks: this process's part in a run over MPI ranks (run.hpp), or none.
void solve(const SolveOptions& o, const cli::CommonOptions& common, const solver::RankRun* ranks = nullptr) {
  solver::SolveRequest request{o.scenario_file, o.mesh_dir, common.output, o.restart_dir, std::nullopt, o.resume, o.overrides};
  request.follower = ranks && ranks->rank != 0;
  if (*o.end_time_option) request.end_time = o.end_time;
  if (o.restart_dir.empty() && o.scenario_file.empty()) throw CLI::RequiredError("scenario");
  if (!o.partition.empty() && !ranks) throw InputError("command line", "--partition", "a run under mpirun (the atoms' ranks)", o.partition);
  if (ranks && ranks->rank != 0) log::set_level(log::Level::quiet);  // rank 0 speaks for the run
  solver::PreparedRun run = solver::prepare_run(request);            // a restart's scenario, output and checkpoint (checkpoint.hpp)
  // Every rank has read the checkpoint before rank 0 takes the folder, and it is the same one.
  if (ranks) ranks->check_same_restart(run.from ? run.from->step + 1 : 0);
  if (ranks && ranks->rank != 0) return solver::follow_simulation(run.scenario, run.from ? &*run.from : nullptr, *ranks);
  const std::string scenario_file = run.scenario_file.string();
  const nlohmann::json reference = o.check_file.empty() ? nlohmann::json() : read_reference(o.check_file);
  // A reference replaces only a reference tactus wrote there (its manifest says so), checked before the run.
  std::optional<OutputFiles> reference_out;
  if (!o.write_reference.empty()) reference_out.emplace(std::vector<std::filesystem::path>{o.write_reference}, common.output_rules({scenario_file}));
  OutputFolder output(run.output, common.output_rules(solver::scenario_inputs(run.scenario)), run.from ? run.from->staging : std::filesystem::path());
  const solver::RunSummary summary = solver::run_simulation(run.scenario, output, run.identity, run.from ? &*run.from : nullptr, ranks);
  if (reference_out) {
    write_file(reference_out->staged(0),
               solver::make_reference(summary.run_json, std::filesystem::path(scenario_file).stem().string()).dump(2) + '\n');
    reference_out->commit();
    log::info() << "reference written: " << o.write_reference;
  }
  if (!o.check_file.empty()) check_against(summary, reference, o.check_file);
}

}  // namespace

#ifdef TACTUS_MPI
// Under mpirun: every rank runs the command, rank 0 alone writes and speaks. A failure every rank
// meets at the same point (bad input, a numerical failure) ends them all with rank 0's message and
// exit code; one rank's own failure (a full disk on rank 0, a file missing on another machine) is
// printed with its rank and ends every rank within 10 s (MPI_Abort). A rank that succeeded waits
// for the others however long rank 0 takes to write (and then fails only if rank 0 does, after
// the run: a --check beyond tolerance, its exit code).
int run_on_ranks(CLI::App& app, int argc, char** argv, cli::CommonOptions& common, const SolveOptions& options, const Tools& tools,
                 solver::RankSession& session) {
  // The other ranks say nothing (their output would repeat rank 0's); their errors are kept for the
  // case where they are theirs alone.
  std::ostringstream follower_errors, follower_output;
  std::streambuf* const cerr = session.rank() == 0 ? nullptr : std::cerr.rdbuf(follower_errors.rdbuf());
  std::streambuf* const cout = session.rank() == 0 ? nullptr : std::cout.rdbuf(follower_output.rdbuf());
  const int code = cli::run(app, argc, argv, common, [&] {
    session.check_same_build();
    if (tools.run(common)) return;
    const solver::RankRun ranks = session.run(options.partition);
    solve(options, common, &ranks);
  });
  if (cerr) {
    std::cerr.rdbuf(cerr);
    std::cout.rdbuf(cout);
  }
  if (session.all_stopped_within(code == 0 ? std::numeric_limits<double>::infinity() : 10.0)) return code;
  if (session.rank() != 0) std::cerr << "tactus-solve (MPI rank " << session.rank() << "): " << follower_errors.str();
  std::cerr << "tactus-solve: MPI rank " << session.rank() << " stopped (exit code " << code << ") while the other ranks ran on: ending them all\n";
  session.abort(code);
}
#endif

int main(int argc, char** argv) {
  CLI::App app{"tactus-solve: explicit total-Lagrangian dynamics (HGO soft tissue, elastic bone) of a scenario.toml", "tactus-solve"};
  cli::CommonOptions common;
  cli::add_common_options(app, common, "output folder for results (default: results next to the scenario)");
  SolveOptions options;
  add_solve_options(app, options);
  app.require_subcommand(0, 1);
  const Tools tools(app);
#ifdef TACTUS_MPI
  if (solver::started_by_mpirun()) {
    solver::RankSession session(&argc, &argv);
    return run_on_ranks(app, argc, argv, common, options, tools, session);
  }
#else
  // Several copies of a build without MPI would each run the whole model into the same folder.
  if (const char* n = std::getenv("OMPI_COMM_WORLD_SIZE"); n && std::atoi(n) > 1) {
    std::cerr << "tactus-solve: error: started by mpirun on " << n
              << " processes, but this tactus-solve was built without MPI (TACTUS_MPI=OFF): rebuild with libopenmpi-dev installed, "
                 "or run it without mpirun\n";
    return 1;
  }
#endif
  return cli::run(app, argc, argv, common, [&] {
    if (!tools.run(common)) solve(options, common);
  });
}
