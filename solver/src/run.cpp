// A whole run: scenario -> model -> explicit steps -> the results folder (run.hpp), in named
// steps: the runaway guards, the step loop with its outputs and history, and the summary.
#include "tactus/solver/run.hpp"
#include "tactus/solver/model_build.hpp"

#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include <signal.h>

#include <cstdlib>
#include <exception>

#include "output/results.hpp"
#include "tactus/core/contracts.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/interrupt.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/progress.hpp"
#include "tactus/core/state_file.hpp"
#include "tactus/solver/checkpoint.hpp"
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
  if (sc.skeleton) in.push_back(sc.skeleton->file);
  return in;
}

RunSummary run_simulation(const Scenario& sc, const fs::path& output_dir) {
  OutputFolder out(output_dir, {"tactus-solve", scenario_inputs(sc), false});
  return run_simulation(sc, out, run_identity(sc, {}));
}

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// The rows history.csv gets every this many steps.
std::size_t history_interval(const Scenario& sc, double est_steps) {
  return sc.run.history_every > 0 ? static_cast<std::size_t>(sc.run.history_every)
                                  : std::max<std::size_t>(1, static_cast<std::size_t>(est_steps / 2000));
}

// Refused before any step: more steps than run.max_steps, or results that will not fit on the
// disk. The estimate is this run's own: its states (about 15 doubles per node and 16 per tet,
// uncompressed), its history rows, its two newest checkpoints (about 60 doubles per node) and the
// last good state a failure writes. Returns the estimated step count.
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
  const double nodes = static_cast<double>(model.num_nodes), tets = static_cast<double>(model.num_elements);
  const double state_bytes = 8.0 * (15.0 * nodes + 16.0 * tets);
  const auto states = static_cast<double>(solver.schedule().size()) + 1;  // and the initial one
  const double columns = 40.0 + 6.0 * static_cast<double>(model.boundaries.size()) + 19.0 * static_cast<double>(model.bodies.size());
  const double history_bytes = 24.0 * columns * (est_steps / static_cast<double>(history_interval(sc, est_steps)) + states + 1);
  const double checkpoint_bytes = sc.run.checkpoints() ? 2 * 8.0 * (60.0 * nodes + 2.0 * tets) : 0.0;
  const double bytes = state_bytes * (states + 1) + history_bytes + checkpoint_bytes + 64e3;
  std::ostringstream what;
  what << static_cast<long long>(states) << " result states, "
       << static_cast<long long>(est_steps / static_cast<double>(history_interval(sc, est_steps))) << " history rows"
       << (sc.run.checkpoints() ? " and two checkpoints" : "");
  out.require_space(static_cast<std::uintmax_t>(bytes), what.str());
  return est_steps;
}

// The bodies' names when mass scaling is on (their added_mass_ history columns), else none.
std::vector<std::string> mass_scaled_bodies(const Model& model, const ExplicitSolver& solver) {
  std::vector<std::string> names;
  if (solver.mass_scaling())
    for (const BodyRange& b : model.bodies) names.push_back(b.name);
  return names;
}

// The restart tests' way to die like a killed process at a chosen moment, from the environment
// (never set in normal use): TACTUS_KILL_AT="step:N" (at the start of step N) or
// "checkpoint:K:PHASE" (while writing this process's K-th checkpoint, PHASE one of begin, data,
// written, renamed; core/state_file.hpp): the process raises SIGKILL on itself. "interrupt:N":
// a SIGTERM as the interrupt watcher would take it, at the start of step N.
struct KillHook {
  long step = -1, checkpoint = -1, interrupt = -1;
  std::string phase;
  KillHook() {
    const char* spec = std::getenv("TACTUS_KILL_AT");
    if (!spec) return;
    const std::string s = spec;
    char buf[32] = {};
    if (std::sscanf(s.c_str(), "step:%ld", &step) == 1 || std::sscanf(s.c_str(), "interrupt:%ld", &interrupt) == 1) return;
    if (std::sscanf(s.c_str(), "checkpoint:%ld:%31s", &checkpoint, buf) == 2) phase = buf;
  }
  void at_step(std::size_t n) const {
    if (step >= 0 && n == static_cast<std::size_t>(step)) raise(SIGKILL);
    if (interrupt >= 0 && n == static_cast<std::size_t>(interrupt)) request_interrupt_for_testing(SIGTERM);
  }
  void at_checkpoint(std::size_t k, const char* p) const {
    if (checkpoint >= 0 && k == static_cast<std::size_t>(checkpoint) && phase == p) raise(SIGKILL);
  }
};

// The length of the history a checkpoint continues from.
std::uintmax_t history_length(const RestartPoint* from) {
  if (!from) return HistoryWriter::kNew;
  StateArchive a(from->state, from->file.string());
  std::size_t bytes = 0;
  a.io("loop.history_bytes", bytes);
  return bytes;
}

std::vector<std::string> rigid_body_names(const ExplicitSolver& solver) {
  std::vector<std::string> names;
  for (const RigidBody& b : solver.rigid_bodies()) names.push_back(b.name);
  return names;
}

// A state file's name: number 0 is the initial state (t = 0), number k the k-th scheduled output;
// after n outputs the folder holds state_0000 .. state_n.
std::string state_name(std::size_t number) {
  std::ostringstream name;
  name << "state_" << std::setw(4) << std::setfill('0') << number << ".vtu";
  return name.str();
}

// The steps of one run and what they write as they go.
class RunLoop {
 public:
  // ranks: rank 0 of a run over ranks, whose checkpoint part holds part_nodes (and all else).
  RunLoop(const Scenario& sc, const Model& model, ExplicitSolver& solver, OutputFolder& out, double est_steps, const RunIdentity& identity,
          const RestartPoint* from, const RankRun* ranks, std::vector<std::uint32_t> part_nodes)
      : sc_(sc),
        model_(model),
        solver_(solver),
        out_(out),
        folder_(out.path()),
        identity_(identity),
        history_(folder_ / "history.csv", model.boundaries, mass_scaled_bodies(model, solver), history_length(from), rigid_body_names(solver),
                 solver.joint_drive(), solver.grip_regions()),
        history_every_(history_interval(sc, est_steps)),
        progress_("solve", static_cast<std::size_t>(est_steps) + 1),
        next_checkpoint_time_(sc.run.checkpoint_interval),
        last_checkpoint_wall_(std::chrono::steady_clock::now()),
        ranks_(ranks),
        part_nodes_(std::move(part_nodes)) {
    summary_.dt_min = std::numeric_limits<double>::infinity();
    summary_.von_mises_peak.assign(model.blocks.size(), 0.0);
    if (from)
      restore(*from);
    else
      write(state_name(0), solver_.displacement(), solver_.velocity_at_step(), solver_.time(), false);  // the initial state
  }

  // Steps to the end time; a numerical failure writes the last good state and is returned. An
  // interrupt with checkpoints on writes one first and keeps the staging folder for a restart.
  nlohmann::json run() {
    // On ranks every rank writes its part of a checkpoint in this folder, when rank 0 finds one due.
    const bool rank_parts = ranks_ && sc_.run.checkpoints();
    if (rank_parts) ranks_->rank0_text((folder_ / kResumableDir).string());
    try {
      while (true) {
        kill_.at_step(solver_.step_index());
        check_interrupt();
        if (const bool due = checkpoint_due(); rank_parts ? ranks_->rank0_decides(due) : due) write_checkpoint();
        solver_.advance_velocity();
        observe_step();
        solver_.check_energy();
        // On ranks every rank takes part in a state's cell records when its solver says one is due.
        if (ranks_ && scheduled() != solver_.at_output_time())
          throw std::logic_error("run loop: the state schedule and the solver's output times disagree at t = " + std::to_string(solver_.time()));
        if (scheduled()) write_scheduled_state();
        if (solver_.finished()) break;
        if (solver_.relaxed()) {  // dynamic relaxation converged: this state ends the run (relaxation.hpp)
          write_scheduled_state();
          summary_.relaxed_at = solver_.time();
          log::info() << "relaxed at t = " << solver_.time() << " s (step " << solver_.step_index() << "): out-of-balance force "
                      << solver_.relaxation().relative_residual()
                      << " of the internal force, at most damping.residual_tolerance = " << sc_.damping.residual_tolerance;
          break;
        }
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
      if (const JointDrive* drive = solver_.joint_drive(); drive && drive->grasp() && drive->max_kinetic_ratio_in_hold() > 0.05) {
        std::ostringstream w;
        w << "grasp: the hold was dynamic, not quasi-static: kinetic energy reached " << 100 * drive->max_kinetic_ratio_in_hold()
          << " % of the strain energy after t = " << sc_.grasp.ramp_time << " s (above 5 %; a longer ramp_time or more damping.alpha)";
        log::warn(w.str());
      }
      return nullptr;
    } catch (const Interrupted& e) {
      if (!sc_.run.checkpoints() || ranks_) throw;  // (on ranks every rank writes a part: the newest periodic one continues)
      write_checkpoint();
      out_.keep_for_resume();
      std::ostringstream kept;
      kept << "checkpoint written at step " << solver_.step_index() << ", t = " << solver_.time() << " s, kept in " << out_.path().string()
           << ": tactus-solve --restart " << out_.final_path().string() << " continues the run";
      throw Interrupted(e.signal_number(), kept.str());
    } catch (const NumericalError& e) {
      summary_.status = "failed";
      solver_.gather_state();  // every rank meets a numerical failure at the same step (follow_simulation too)
      // The last good state: u^{n-1} (before the failing update), with the half-step velocity.
      write("last_good_state.vtu", solver_.previous_displacement(), solver_.half_step_velocity(), solver_.time() - 0.5 * solver_.time_step());
      return e.what();
    } catch (const WriteError& e) {
      throw keep_checkpoints(e);
    }
  }

  // A write that failed (a full disk, say) ends the run, but not its work: the newest checkpoint
  // stays in the staging folder, and the error says how to continue once the cause is mended.
  WriteError keep_checkpoints(const WriteError& e) {
    const std::vector<CheckpointListing> kept = list_checkpoints(folder_ / kResumableDir);
    if (kept.empty())
      return e.with_note(sc_.run.checkpoints() ? "; no checkpoint was written yet, so the run must start again"
                                               : "; free some space and run again (with run.checkpoint_interval, such a run can be continued)");
    out_.keep_for_resume();
    return e.with_note("; the run's newest checkpoint (" + kept.front().manifest.filename().string() + ") is kept in " + out_.path().string() +
                       (e.no_space() ? ": free some space, then" : ": mend the cause, then") + " tactus-solve --restart " +
                       out_.final_path().string() + " continues the run from it");
  }

  // The run's last writes (history, listing, run.json), with the same care for its checkpoints.
  template <class F>
  void finishing(F&& write) {
    try {
      write();
    } catch (const WriteError& e) {
      throw keep_checkpoints(e);
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
    if (summary_.status == "completed" && next_out_ != solver_.schedule().size() && summary_.relaxed_at < 0) {
      summary_.status = "failed";
      failure = "wrote " + std::to_string(next_out_) + " of the " + std::to_string(solver_.schedule().size()) + " scheduled states";
    }
    write_pvd(folder_ / "results.pvd", pvd_);
    return failure;
  }

  RunSummary& summary() { return summary_; }
  const RunPeaks& peaks() const { return peaks_; }
  // The checkpoints are the run's own business: a finished run (completed or failed) drops them.
  void drop_checkpoints() {
    std::error_code ec;
    fs::remove_all(folder_ / kResumableDir, ec);
  }

 private:
  bool checkpoint_due() {
    const RunSpec& r = sc_.run;
    if (r.checkpoint_interval > 0 && solver_.time() >= next_checkpoint_time_ && !solver_.finished()) {
      // The next multiple of the interval after t (one jump: a step may pass several).
      next_checkpoint_time_ += r.checkpoint_interval;
      if (next_checkpoint_time_ <= solver_.time())
        next_checkpoint_time_ = r.checkpoint_interval * (std::floor(solver_.time() / r.checkpoint_interval) + 1);
      if (next_checkpoint_time_ <= solver_.time()) next_checkpoint_time_ = std::nextafter(solver_.time(), kInfinity);
      return true;
    }
    return r.checkpoint_wall_interval > 0 &&
           std::chrono::duration<double>(std::chrono::steady_clock::now() - last_checkpoint_wall_).count() >= r.checkpoint_wall_interval;
  }

  // checkpoints/checkpoint_<step>.h5 of the state at the start of this step (checkpoint.hpp); the
  // newest two are kept.
  void write_checkpoint() {
    const std::size_t k = checkpoints_written_++;
    kill_.at_checkpoint(k, "begin");
    StateArchive a;
    a.arrays().kind = kCheckpointKind;
    identity_.io(a);
    solver_.checkpoint(a);
    loop_state(a);
    const auto phase = [&](const char* p) { kill_.at_checkpoint(k, p); };
    const fs::path manifest = ranks_ ? CheckpointStore(folder_ / kResumableDir, 0, ranks_->ranks)
                                           .write(solver_.step_index(), solver_.time(),
                                                  checkpoint_part(a.arrays(), part_nodes_, model_.num_nodes, true), phase, 2, ranks_->all_meet)
                                     : CheckpointStore(folder_ / kResumableDir).write(solver_.step_index(), solver_.time(), a.arrays(), phase);
    last_checkpoint_wall_ = std::chrono::steady_clock::now();
    log::debug() << "checkpoint at step " << solver_.step_index() << ", t = " << solver_.time() << " s: " << manifest.string();
  }

  // The loop's own part of a checkpoint (both directions).
  void loop_state(StateArchive& a) {
    std::size_t history_bytes = a.loading() ? 0 : history_.flush();
    a.io("loop.history_bytes", history_bytes);
    a.io("loop.next_output", next_out_);
    std::vector<double> pvd_times;
    std::string pvd_names;
    for (const auto& [t, file] : pvd_) pvd_times.push_back(t), pvd_names += file + '\n';
    a.io("loop.pvd_times", pvd_times), a.io("loop.pvd_files", pvd_names);
    if (a.loading()) {
      pvd_.clear();
      std::istringstream names(pvd_names);
      std::string file;
      for (double t : pvd_times) std::getline(names, file), pvd_.emplace_back(t, file);
    }
    a.io("loop.next_checkpoint_time", next_checkpoint_time_);
    std::vector<std::size_t> restart_steps;
    std::vector<double> restart_times;
    for (const auto& [step, time] : summary_.restarts) restart_steps.push_back(step), restart_times.push_back(time);
    a.io("loop.restart_steps", restart_steps), a.io("loop.restart_times", restart_times, restart_steps.size());
    if (a.loading()) {
      summary_.restarts.clear();
      for (std::size_t k = 0; k < restart_steps.size(); ++k) summary_.restarts.emplace_back(restart_steps[k], restart_times[k]);
    }
    a.io("loop.summary.dt_min", summary_.dt_min), a.io("loop.summary.dt_max", summary_.dt_max);
    a.io("loop.summary.max_relative_balance_error", summary_.max_relative_balance_error);
    a.io("loop.summary.outputs", summary_.outputs);
    a.io("loop.summary.von_mises_peak", summary_.von_mises_peak, summary_.von_mises_peak.size());
    RunPeaks& p = peaks_;
    for (auto [name, x] : {std::pair<const char*, double*>{"force", &p.force},
                           {"force_time", &p.force_time},
                           {"area", &p.area},
                           {"area_time", &p.area_time},
                           {"pressure", &p.pressure},
                           {"pressure_time", &p.pressure_time},
                           {"step_pressure", &p.step_pressure},
                           {"step_pressure_time", &p.step_pressure_time}})
      a.io(std::string("loop.peaks.") + name, *x);
    a.io_record("loop.peaks.pressure_at", p.pressure_at);
    a.io("loop.peaks.pressure_node", p.pressure_node), a.io("loop.peaks.max_iterations", p.max_iterations);
    a.io("loop.peaks.unconverged_steps", p.unconverged_steps), a.io("loop.peaks.contact_steps", p.contact_steps);
    a.io("loop.peaks.recovering_rows", p.recovering_rows);
    a.io("loop.peaks.rows_swept", p.rows_swept), a.io("loop.peaks.rows_in_order", p.rows_in_order);
    a.io("loop.peaks.von_mises", p.von_mises), a.io("loop.peaks.reaction_peak", p.reaction_peak);
    a.io("loop.peaks.reaction_peak_time", p.reaction_peak_time), a.io("loop.peaks.reaction_peak_force", p.reaction_peak_force);
    a.io_records("loop.peaks.pairs", p.pairs), a.io_records("loop.peaks.at_outputs", p.at_outputs);
  }

  // The loop's restored bookkeeping against the run (the integrator checks its own state).
  void validate_loop_state(const StateArchive& a) const {
    const double t = solver_.time(), interval = sc_.run.checkpoint_interval;
    if (next_out_ > solver_.schedule().size() || (next_out_ < solver_.schedule().size() && solver_.schedule()[next_out_] < t))
      a.invalid("loop.next_output", "the next output state of the run's schedule after t = " + std::to_string(t) + " s", std::to_string(next_out_));
    if (!std::isfinite(next_checkpoint_time_) || next_checkpoint_time_ < 0 || (interval > 0 && next_checkpoint_time_ > t + interval * (1 + 1e-9)))
      a.invalid("loop.next_checkpoint_time", "a time within one checkpoint_interval after t = " + std::to_string(t) + " s",
                std::to_string(next_checkpoint_time_));
    for (const auto& [time, file] : pvd_) {
      unsigned index = 0;
      char rest = 0;
      if (!std::isfinite(time) || time > t || std::sscanf(file.c_str(), "results/state_%u.vtu%c", &index, &rest) != 1 || index > next_out_)
        a.invalid("loop.pvd_files", "the states written before t = " + std::to_string(t) + " s (results/state_NNNN.vtu)", "'" + file + "'");
    }
  }

  // Continues from a checkpoint: the state, the bookkeeping, and the results folder as it was
  // then (states written after it, and half-written files of the killed process, go).
  void restore(const RestartPoint& from) {
    StateArchive a(from.state, from.file.string());
    solver_.checkpoint(a);
    loop_state(a);
    validate_loop_state(a);
    summary_.restarts.emplace_back(from.step, from.time);
    std::error_code ec;
    for (auto it = fs::directory_iterator(folder_ / "results", ec); !ec && it != fs::directory_iterator(); it.increment(ec)) {
      const std::string name = it->path().filename().string();
      unsigned index = 0;
      const bool later_state = std::sscanf(name.c_str(), "state_%u.vtu", &index) == 1 && index > next_out_;
      if (later_state || name.find(".partial-") != std::string::npos) fs::remove(it->path());
    }
    for (const auto& e : fs::directory_iterator(folder_ / kResumableDir))
      if (e.path().filename().string().find(".partial-") != std::string::npos) fs::remove(e.path());
    log::info() << "continuing from " << from.file.string() << ": step " << from.step << ", t = " << from.time << " s";
  }

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
    if (cr.recovering > 0 && peaks_.recovering_rows == cr.recovering) {  // the first step with one
      const std::size_t node = model_.input_node(static_cast<std::size_t>(cr.deepest_node));
      const BodyRange& body = model_.bodies[model_.body_of_node(node)];
      std::ostringstream w;
      w << "contact: node " << node - body.node_begin + 1 << " of body '" << body.name << "' found " << -cr.deepest_gap * 1e3
        << " mm inside its master at step " << solver_.step_index() << ", t = " << t
        << " s (a penetration the previous step did not make): pushed out at contact_solver.recovery_speed = " << sc_.contact_solver.recovery_speed
        << " m/s rather than in one step (reported once; run.json contact.uzawa.recovering_rows counts such rows)";
      log::warn(w.str());
    }
    if (!cr.converged) {
      if (peaks_.unconverged_steps == 0) {
        std::ostringstream w;
        w << "contact: Uzawa iterations stopped at contact_solver.max_iterations = " << sc_.contact_solver.max_iterations << " with residual "
          << cr.residual << " at step " << solver_.step_index() << " (reported once; count in run.json)";
        log::warn(w.str());
      }
      ++peaks_.unconverged_steps;
    }
    if (solver_.step_index() % history_every_ == 0 || scheduled() || solver_.finished()) {
      solver_.sum_grip_regions();
      history_.write({solver_.step_index(), t, solver_.last_step(), solver_.critical_step(), &en, &cr, peak_at, &solver_.reactions(),
                      solver_.mass_scaling() ? &solver_.added_mass() : nullptr, &solver_.rigid_bodies(), solver_.joint_drive(),
                      solver_.grip_regions()});
    }
  }

  void write_scheduled_state() {  // the solver lands on every scheduled time exactly
    write(state_name(next_out_ + 1), solver_.displacement(), solver_.velocity_at_step(), solver_.time());
    ++next_out_;
  }

  // A state file; `output` adds its contact row to run.json's contact.at_outputs (the scheduled
  // outputs and the last good state; the initial state has had no contact step yet).
  void write(const std::string& name, const std::vector<double>& u, const std::vector<double>& v, double t, bool output = true) {
    const CellRecords records = [&](const CellSink& sink) { solver_.cell_records(u, v, sink); };
    const std::vector<double> vm = write_state(model_, folder_ / "results" / name, u, v, records, &solver_.contact(), t, solver_.grip_regions());
    for (std::size_t b = 0; b < vm.size(); ++b) summary_.von_mises_peak[b] = std::max(summary_.von_mises_peak[b], vm[b]);
    if (output && !solver_.contact().empty()) {
      const ContactStepReport& cr = solver_.contact_report();
      const ContactSolver::AveragedPressure avg = solver_.contact().averaged_peak_pressure(u.data(), sc_.contact_solver.pressure_average_area);
      peaks_.at_outputs.push_back({t, cr.normal_force, cr.area, cr.peak_pressure, avg.value, avg.at, cr.windowed_normal_force, cr.windowed_area});
    }
    pvd_.emplace_back(t, "results/" + name);
    ++summary_.outputs;
  }

  const Scenario& sc_;
  const Model& model_;
  ExplicitSolver& solver_;
  OutputFolder& out_;
  fs::path folder_;
  RunIdentity identity_;
  HistoryWriter history_;
  std::size_t history_every_;
  Progress progress_;
  RunSummary summary_;
  RunPeaks peaks_;
  std::vector<std::pair<double, std::string>> pvd_;
  std::size_t next_out_ = 0;
  double next_checkpoint_time_;
  std::chrono::steady_clock::time_point last_checkpoint_wall_;
  std::size_t checkpoints_written_ = 0;  // by this process
  KillHook kill_;
  const RankRun* ranks_;
  std::vector<std::uint32_t> part_nodes_;
};

}  // namespace

namespace {

// On ranks: this rank's part of the stress pass, at run.threads per rank (1 unless given).
std::unique_ptr<StressPassEngine> rank_stress_pass(const Model& model, const Scenario& sc, const RankRun* ranks) {
  if (!ranks) return nullptr;
  return ranks->stress_pass(model, sc.damping.beta, sc.run.threads > 0 ? sc.run.threads : 1);
}

// What every rank measured, for run.json's "ranks" (collective).
nlohmann::json rank_report(StressPassEngine* shared, const Model& model, const ExplicitSolver& solver, std::chrono::steady_clock::time_point start) {
  if (!shared) return nullptr;
  return shared->report({{"stress_passes_s", solver.stress_seconds()},
                         {"contact_s", solver.contact_seconds()},
                         {"wall_time_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()},
                         {"model_bytes", static_cast<double>(model.memory_bytes())},
                         {"solver_bytes", static_cast<double>(solver.memory_bytes())}});
}

}  // namespace

void follow_simulation(const Scenario& sc, const RestartPoint* from, const RankRun& ranks) {
  const auto wall_start = std::chrono::steady_clock::now();
  Model model = build_model(sc);
  const std::unique_ptr<StressPassEngine> shared = rank_stress_pass(model, sc, &ranks);
  ExplicitSolver solver(model, sc.run, sc.damping, shared.get());
  // Rank 0's writes, in which every rank computes its own tets' cell records.
  const auto state_records = [&](const std::vector<double>& u, const std::vector<double>& v) { solver.cell_records(u, v, [](auto...) {}); };
  if (from) {
    StateArchive a(from->state, from->file.string());
    solver.checkpoint(a);  // (its check runs this process's pass over the whole model, once)
  }
  // The pass holds this rank's tets' geometry and nodes: the model's go once the restart check has
  // run (as on rank 0), before the initial state.
  model.release_tet_geometry();
  if (!from) state_records(solver.displacement(), solver.velocity_at_step());
  // RunLoop::run's steps, less its writes but for this rank's part of each checkpoint and its
  // tets' part of each state (the collectives in those).
  const bool rank_parts = sc.run.checkpoints();
  const std::string folder = rank_parts ? ranks.rank0_text("") : "";
  const std::vector<std::uint32_t> part_nodes = shared->checkpoint_nodes();
  std::exception_ptr failure;
  try {
    while (true) {
      if (rank_parts && ranks.rank0_decides(false)) {
        StateArchive a;
        a.arrays().kind = kCheckpointKind;
        solver.checkpoint(a);
        CheckpointStore(folder, ranks.rank, ranks.ranks)
            .write(solver.step_index(), solver.time(), checkpoint_part(a.arrays(), part_nodes, model.num_nodes, false));
        ranks.all_meet();
      }
      solver.advance_velocity();
      solver.check_energy();
      if (solver.at_output_time()) state_records(solver.displacement(), solver.velocity_at_step());
      if (solver.finished()) break;
      if (solver.relaxed()) {
        state_records(solver.displacement(), solver.velocity_at_step());
        break;
      }
      solver.advance_position();
    }
  } catch (const NumericalError&) {
    failure = std::current_exception();
    solver.gather_state();  // as rank 0 does before it writes the last good state
    state_records(solver.previous_displacement(), solver.half_step_velocity());
  }
  rank_report(shared.get(), model, solver, wall_start);
  if (failure) std::rethrow_exception(failure);
}

RunSummary run_simulation(const Scenario& sc, OutputFolder& staged, const RunIdentity& identity, const RestartPoint* from, const RankRun* ranks) {
  const auto wall_start = std::chrono::steady_clock::now();
  Model model = build_model(sc);
  log::info() << "model: " << model.num_nodes << " nodes, " << model.num_elements << " tets, " << model.blocks.size() << " materials, "
              << sc.bodies.size() << " bodies";
  for (const MaterialBlock& b : model.blocks)
    log::info() << "  " << b.name << ": " << b.material.type_name() << ", " << (b.end - b.begin) << " tets, "
                << (b.material.anp() ? "average-nodal-pressure (ANP) tets" : "standard tets");
  const std::unique_ptr<StressPassEngine> shared = rank_stress_pass(model, sc, ranks);
  ExplicitSolver solver(model, sc.run, sc.damping, shared.get());
  log::info() << "time step " << solver.time_step() << " s (safety " << sc.run.time_step_safety << "; " << solver.describe_step_limit() << "), "
              << solver.threads() << " threads" << (shared ? " per rank on " + std::to_string(shared->ranks()) + " MPI ranks" : "")
              << (sc.run.threads == 0 && solver.threads() > 1 ? " (or 1 while that is faster: automatic)" : "");
  const double est_steps = check_runaway(sc, model, solver, staged);

  fs::create_directories(staged.path() / "results");
  // On ranks the pass holds this rank's tets' geometry and nodes: the model's go (every tet's
  // nodes, gradients, volumes and law data; the model's scatter will not build them here at all),
  // before the initial state is written, or once the restart check (in the loop's restore) has run.
  const bool release = shared && shared->holds_own_geometry();
  if (release && !from) model.release_tet_geometry();
  RunLoop loop(sc, model, solver, staged, est_steps, identity, from, ranks, shared ? shared->checkpoint_nodes() : std::vector<std::uint32_t>{});
  if (release && from) model.release_tet_geometry();
  nlohmann::json failure = loop.run();
  loop.finishing([&] { failure = loop.finish(failure); });
  RunSummary& summary = loop.summary();
  summary.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  const nlohmann::json per_rank = rank_report(shared.get(), model, solver, wall_start);
  summary.run_json = run_json(sc, model, solver, summary, loop.peaks(), failure);
  if (shared) summary.run_json[contracts::run_json::ranks] = per_rank;
  loop.finishing([&] { write_file(staged.path() / "run.json", summary.run_json.dump(2) + '\n'); });
  loop.drop_checkpoints();  // the run is complete: they are no part of its results
  staged.commit();
  const Energies& en = solver.energies();
  log::info() << summary.status << ": " << summary.steps << " steps to t = " << summary.end_time << " s in " << summary.wall_seconds
              << " s; energy balance error " << std::abs(en.balance_error()) / en.scale() * 100 << " % of the largest energy; " << summary.outputs
              << " states; results in " << staged.final_path().string();
  if (const ThreadTuner& t = solver.thread_tuner(); t.probes() > 0)
    log::verbose() << "automatic threads: " << t.probes() << " probe(s) of " << solver.threads() << " threads against 1, " << t.probes_choosing_one()
                   << " found 1 thread faster for the stress passes, " << solver.contact_thread_tuner().probes_choosing_one() << " of "
                   << solver.contact_thread_tuner().probes() << " for the contact sweep (thread_tuner.hpp)";
  if (summary.status == "failed")
    throw NumericalError(failure.get<std::string>() + " (last good state and history written to " + staged.final_path().string() + ")");
  return summary;
}

}  // namespace tactus::solver
