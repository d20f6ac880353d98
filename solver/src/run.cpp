// A whole run: scenario -> model -> explicit steps -> the results folder (run.hpp), in named
// steps: the runaway guards, the step loop with its outputs and history, and the summary.
#include "tactus/solver/run.hpp"

#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "output/results.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/interrupt.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/progress.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/model.hpp"

namespace fs = std::filesystem;

namespace tactus::solver {

std::vector<fs::path> scenario_inputs(const Scenario& sc) {
  std::vector<fs::path> in{sc.file};
  for (const auto& b : sc.bodies) {
    in.push_back(b.mesh);
    if (!b.fibres.empty()) in.push_back(b.fibres);
  }
  return in;
}

RunSummary run_simulation(const Scenario& sc, const fs::path& output_dir) {
  OutputFolder out(output_dir, {"tactus-solve", scenario_inputs(sc), false});
  return run_simulation(sc, out);
}

namespace {

// Refused before any step: more steps than run.max_steps, or states that will not fit on the disk
// (about 15 doubles per node and 16 per tet, uncompressed). Returns the estimated step count.
double check_runaway(const Scenario& sc, const Model& model, const ExplicitSolver& solver, OutputFolder& out) {
  const double est_steps = sc.run.end_time / std::max(solver.time_step(), 1e-300);
  if (est_steps > sc.run.max_steps) {
    std::ostringstream f;
    f << "about " << est_steps << " steps (end time " << sc.run.end_time << " s at " << solver.time_step() << " s per step, "
      << solver.describe_step_limit() << ")";
    throw InputError(
        sc.file.string(), "run.end_time",
        "a run of at most run.max_steps = " + std::to_string(static_cast<long long>(sc.run.max_steps)) + " steps (raise run.max_steps to allow it)",
        f.str());
  }
  const double state_bytes = 8.0 * (15.0 * static_cast<double>(model.num_nodes) + 16.0 * static_cast<double>(model.num_elements));
  const auto states = solver.schedule().size();
  out.require_space(static_cast<std::uintmax_t>(state_bytes * static_cast<double>(states) + 2e5 * 200), std::to_string(states) + " result states");
  return est_steps;
}

// The bodies' names when mass scaling is on (their added_mass_ history columns), else none.
std::vector<std::string> mass_scaled_bodies(const Model& model, const ExplicitSolver& solver) {
  std::vector<std::string> names;
  if (solver.mass_scaling())
    for (const BodyRange& b : model.bodies) names.push_back(b.name);
  return names;
}

// The steps of one run and what they write as they go.
class RunLoop {
 public:
  RunLoop(const Scenario& sc, const Model& model, ExplicitSolver& solver, const fs::path& folder, double est_steps)
      : sc_(sc),
        model_(model),
        solver_(solver),
        folder_(folder),
        history_(folder / "history.csv", model.boundaries, mass_scaled_bodies(model, solver)),
        history_every_(sc.run.history_every > 0 ? static_cast<std::size_t>(sc.run.history_every)
                                                : std::max<std::size_t>(1, static_cast<std::size_t>(est_steps / 2000))),
        progress_("solve", static_cast<std::size_t>(est_steps) + 1) {
    summary_.dt_min = std::numeric_limits<double>::infinity();
    summary_.von_mises_peak.assign(model.blocks.size(), 0.0);
  }

  // Steps to the end time; a numerical failure writes the last good state and is returned.
  nlohmann::json run() {
    try {
      while (true) {
        check_interrupt();
        solver_.advance_velocity();
        observe_step();
        solver_.check_energy();
        if (scheduled()) write_scheduled_state();
        if (solver_.finished()) break;
        solver_.advance_position();
        summary_.dt_min = std::min(summary_.dt_min, solver_.last_step());
        summary_.dt_max = std::max(summary_.dt_max, solver_.last_step());
        if (progress_.due()) {
          std::ostringstream note;
          note << "t=" << solver_.time() << " s dt=" << solver_.time_step();
          progress_.update(solver_.step_index(), note.str());
        }
      }
      summary_.status = "completed";
      return nullptr;
    } catch (const NumericalError& e) {
      summary_.status = "failed";
      // The last good state: u^{n-1} (before the failing update), with the half-step velocity.
      write("last_good_state.vtu", solver_.previous_displacement(), solver_.half_step_velocity(), solver_.time() - 0.5 * solver_.time_step());
      return e.what();
    }
  }

  // Closes the files; a completed run that wrote fewer states than scheduled is a failure.
  nlohmann::json finish(nlohmann::json failure) {
    progress_.finish();
    history_.close();
    summary_.steps = solver_.step_index();
    summary_.end_time = solver_.time();
    summary_.energy_balance_error = solver_.energies().balance_error();
    if (summary_.steps == 0) summary_.dt_min = summary_.dt_max = 0;
    if (summary_.status == "completed" && next_out_ != solver_.schedule().size()) {
      summary_.status = "failed";
      failure = "wrote " + std::to_string(next_out_) + " of the " + std::to_string(solver_.schedule().size()) + " scheduled states";
    }
    write_pvd(folder_ / "results.pvd", pvd_);
    return failure;
  }

  RunSummary& summary() { return summary_; }
  const RunPeaks& peaks() const { return peaks_; }

 private:
  bool scheduled() const { return next_out_ < solver_.schedule().size() && solver_.time() == solver_.schedule()[next_out_]; }

  // Peaks, the Uzawa warning and the history row of the state just computed (t^n).
  void observe_step() {
    const Energies& en = solver_.energies();
    const double t = solver_.time();
    summary_.max_relative_balance_error = std::max(summary_.max_relative_balance_error, std::abs(en.balance_error()) / en.scale());
    const ContactStepReport& cr = solver_.contact_report();
    Vec3 peak_at{0, 0, 0};
    if (cr.peak_node >= 0)
      for (int c = 0; c < 3; ++c) peak_at[c] = model_.X[3 * cr.peak_node + c] + solver_.displacement()[3 * cr.peak_node + c];
    peaks_.add_contact_step(cr, t, peak_at, solver_.contact().pair_reports());
    peaks_.add_reactions(solver_.reactions(), t);
    if (!cr.converged) {
      if (peaks_.unconverged_steps == 0) {
        std::ostringstream w;
        w << "contact: Uzawa iterations stopped at contact_solver.max_iterations = " << sc_.contact_solver.max_iterations << " with residual "
          << cr.residual << " at step " << solver_.step_index() << " (reported once; count in run.json)";
        log::warn(w.str());
      }
      ++peaks_.unconverged_steps;
    }
    if (solver_.step_index() % history_every_ == 0 || scheduled() || solver_.finished())
      history_.write({solver_.step_index(), t, solver_.last_step(), solver_.critical_step(), &en, &cr, peak_at, &solver_.reactions(),
                      solver_.mass_scaling() ? &solver_.added_mass() : nullptr});
  }

  void write_scheduled_state() {  // the solver lands on every scheduled time exactly
    std::ostringstream name;
    name << "state_" << std::setw(4) << std::setfill('0') << next_out_ << ".vtu";
    write(name.str(), solver_.displacement(), solver_.velocity_at_step(), solver_.time());
    ++next_out_;
  }

  void write(const std::string& name, const std::vector<double>& u, const std::vector<double>& v, double t) {
    const std::vector<double> vm = write_state(model_, folder_ / "results" / name, u, v, &solver_.contact());
    for (std::size_t b = 0; b < vm.size(); ++b) summary_.von_mises_peak[b] = std::max(summary_.von_mises_peak[b], vm[b]);
    if (!solver_.contact().empty()) {
      const ContactStepReport& cr = solver_.contact_report();
      const ContactSolver::AveragedPressure avg = solver_.contact().averaged_peak_pressure(u.data(), sc_.contact_solver.pressure_average_area);
      peaks_.at_outputs.push_back({t, cr.normal_force, cr.area, cr.peak_pressure, avg.value, avg.at});
    }
    pvd_.emplace_back(t, "results/" + name);
    ++summary_.outputs;
  }

  const Scenario& sc_;
  const Model& model_;
  ExplicitSolver& solver_;
  fs::path folder_;
  HistoryWriter history_;
  std::size_t history_every_;
  Progress progress_;
  RunSummary summary_;
  RunPeaks peaks_;
  std::vector<std::pair<double, std::string>> pvd_;
  std::size_t next_out_ = 0;
};

}  // namespace

RunSummary run_simulation(const Scenario& sc, OutputFolder& staged) {
  const auto wall_start = std::chrono::steady_clock::now();
  const Model model = build_model(sc);
  log::info() << "model: " << model.num_nodes << " nodes, " << model.num_elements << " tets, " << model.blocks.size() << " materials, "
              << sc.bodies.size() << " bodies";
  for (const MaterialBlock& b : model.blocks)
    log::info() << "  " << b.name << ": " << b.material.type_name() << ", " << (b.end - b.begin) << " tets, "
                << (b.material.anp() ? "average-nodal-pressure (ANP) tets" : "standard tets");
  ExplicitSolver solver(model, sc.run, sc.damping);
  log::info() << "time step " << solver.time_step() << " s (safety " << sc.run.time_step_safety << "; " << solver.describe_step_limit() << "), "
              << solver.threads() << " threads";
  const double est_steps = check_runaway(sc, model, solver, staged);

  fs::create_directories(staged.path() / "results");
  RunLoop loop(sc, model, solver, staged.path(), est_steps);
  const nlohmann::json failure = loop.finish(loop.run());
  RunSummary& summary = loop.summary();
  summary.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  summary.run_json = run_json(sc, model, solver, summary, loop.peaks(), failure);
  std::ofstream(staged.path() / "run.json") << summary.run_json.dump(2) << '\n';
  staged.commit();
  const Energies& en = solver.energies();
  log::info() << summary.status << ": " << summary.steps << " steps to t = " << summary.end_time << " s in " << summary.wall_seconds
              << " s; energy balance error " << std::abs(en.balance_error()) / en.scale() * 100 << " % of the largest energy; " << summary.outputs
              << " states; results in " << staged.final_path().string();
  if (summary.status == "failed")
    throw NumericalError(failure.get<std::string>() + " (last good state and history written to " + staged.final_path().string() + ")");
  return summary;
}

}  // namespace tactus::solver
