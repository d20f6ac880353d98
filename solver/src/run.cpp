#include "tactus/solver/run.hpp"

#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/core/interrupt.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/progress.hpp"
#include "tactus/core/version.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/internal_force.hpp"
#include "tactus/solver/model.hpp"

namespace fs = std::filesystem;

namespace tactus::solver {

namespace {

// Cell and point fields of one state, in the input numbering.
// Returns the largest von Mises stress of each material block in this state.
std::vector<double> write_state(const Model& m, const fs::path& file, const std::vector<double>& u, const std::vector<double>& v,
                                const ContactSolver* contact) {
  std::vector<double> block_peak(m.blocks.size(), 0.0);
  const std::size_t N = m.num_nodes, E = m.num_elements;
  MeshField disp{"displacement", 3, std::vector<double>(3 * N)}, vel{"velocity", 3, std::vector<double>(3 * N)};
  std::vector<Vec3> current(N);
  for (std::size_t i = 0; i < N; ++i) {
    const std::size_t k = static_cast<std::size_t>(m.node_of_input[i]);
    for (int c = 0; c < 3; ++c) {
      disp.values[3 * i + c] = u[3 * k + c];
      vel.values[3 * i + c] = v[3 * k + c];
      current[i][c] = m.X[3 * k + c] + u[3 * k + c];
    }
  }
  std::vector<MeshField> point_fields{disp, vel};
  if (contact && !contact->empty()) {
    // Contact at this time: pressure r_n / A, tangential traction r_t / A, status, gap (docs/design.md).
    std::vector<double> pressure, traction, status, gap;
    contact->node_fields(pressure, traction, status, gap);
    MeshField p{"contact_pressure", 1, std::vector<double>(N)}, t{"contact_traction", 3, std::vector<double>(3 * N)},
        st{"contact_status", 1, std::vector<double>(N)}, g{"contact_gap", 1, std::vector<double>(N)};
    for (std::size_t i = 0; i < N; ++i) {
      const std::size_t k = static_cast<std::size_t>(m.node_of_input[i]);
      p.values[i] = pressure[k], st.values[i] = status[k], g.values[i] = gap[k];
      for (int c = 0; c < 3; ++c) t.values[3 * i + c] = traction[3 * k + c];
    }
    point_fields.push_back(std::move(p));
    point_fields.push_back(std::move(t));
    point_fields.push_back(std::move(st));
    point_fields.push_back(std::move(g));
  }
  MeshField stress{"cauchy_stress", 6, std::vector<double>(6 * E)}, vm{"von_mises", 1, std::vector<double>(E)},
      material{"material", 1, std::vector<double>(E)}, jac{"J", 1, std::vector<double>(E)},
      fibre{"fibre_stretch", 2, std::vector<double>(2 * E)}, body{"body", 1, std::vector<double>(E)};
  for (std::size_t b = 0; b < m.bodies.size(); ++b)
    for (std::size_t e = m.bodies[b].tet_begin; e < m.bodies[b].tet_end; ++e) body.values[e] = static_cast<double>(b);
  for (std::size_t bi = 0; bi < m.blocks.size(); ++bi) {
    const MaterialBlock& b = m.blocks[bi];
    for (std::size_t e = b.begin; e < b.end; ++e) {
      const Mat3 F = Mat3::Identity() + nodal_gradient(u.data(), &m.conn[4 * e], &m.grad[9 * e]);
      Vec3d a1 = Vec3d::UnitX(), a2 = Vec3d::UnitY();
      if (const auto* h = std::get_if<Hgo>(&b.material)) {
        a1 = b.element_fibres ? Vec3d(&m.fibres[6 * e]) : h->a1;
        a2 = b.element_fibres ? Vec3d(&m.fibres[6 * e + 3]) : h->a2;
      }
      const Mat3 cof = cofactor(F);
      const double J = F.row(0).dot(cof.row(0));
      Mat3 P;
      if (const auto* h = std::get_if<Hgo>(&b.material))
        P = h->evaluate(F, cof, J, a1, a2).P;
      else
        P = std::visit([&](const auto& mat) { return mat.evaluate(F).P; }, b.material);
      const Mat3 s = cauchy_stress(F, P);
      const std::size_t out = static_cast<std::size_t>(m.input_element[e]);
      const double voigt[6] = {s(0, 0), s(1, 1), s(2, 2), s(0, 1), s(1, 2), s(0, 2)};
      for (int k = 0; k < 6; ++k) stress.values[6 * out + k] = voigt[k];
      vm.values[out] = von_mises(s);
      block_peak[bi] = std::max(block_peak[bi], vm.values[out]);
      material.values[out] = static_cast<double>(bi);
      jac.values[out] = J;
      if (std::holds_alternative<Hgo>(b.material)) {
        fibre.values[2 * out] = (F * a1).norm();
        fibre.values[2 * out + 1] = (F * a2).norm();
      }
    }
  }
  write_vtu(file, m.input_mesh, point_fields, {stress, vm, material, body, jac, fibre}, &current);
  return block_peak;
}

void write_pvd(const fs::path& file, const std::vector<std::pair<double, std::string>>& entries) {
  std::ofstream o(file);
  o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
  o << std::setprecision(12);
  for (const auto& [t, name] : entries) o << "    <DataSet timestep=\"" << t << "\" part=\"0\" file=\"" << name << "\"/>\n";
  o << "  </Collection>\n</VTKFile>\n";
  if (!o) throw InputError(file.string(), "", "a writable file");
}

}  // namespace

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

RunSummary run_simulation(const Scenario& sc, OutputFolder& staged) {
  const fs::path output_dir = staged.final_path();
  const auto wall_start = std::chrono::steady_clock::now();
  const Model model = build_model(sc);
  log::info() << "model: " << model.num_nodes << " nodes, " << model.num_elements << " tets, " << model.blocks.size()
              << " materials, " << sc.bodies.size() << " bodies";
  ExplicitSolver solver(model, sc.run, sc.damping);
  log::info() << "time step " << solver.time_step() << " s (safety " << sc.run.time_step_safety << "; "
              << solver.describe_step_limit() << "), " << solver.threads() << " threads";
  const std::vector<double>& schedule = solver.schedule();

  // Runaway guards, before any step: the number of steps this run would take, and the space its
  // states need (about 15 doubles per node and 16 per tet, uncompressed).
  const double est_steps = sc.run.end_time / std::max(solver.time_step(), 1e-300);
  if (est_steps > sc.run.max_steps) {
    std::ostringstream f;
    f << "about " << est_steps << " steps (end time " << sc.run.end_time << " s at " << solver.time_step() << " s per step, "
      << solver.describe_step_limit() << ")";
    throw InputError(sc.file.string(), "run.end_time",
                     "a run of at most run.max_steps = " + std::to_string(static_cast<long long>(sc.run.max_steps)) +
                         " steps (raise run.max_steps to allow it)",
                     f.str());
  }
  const double state_bytes = 8.0 * (15.0 * static_cast<double>(model.num_nodes) + 16.0 * static_cast<double>(model.num_elements));
  staged.require_space(static_cast<std::uintmax_t>(state_bytes * static_cast<double>(schedule.size()) + 2e5 * 200),
                       std::to_string(schedule.size()) + " result states");

  fs::create_directories(staged.path() / "results");
  std::vector<std::pair<double, std::string>> pvd;
  std::ofstream history(staged.path() / "history.csv");
  history << "step,time,dt,kinetic_energy,internal_energy,damping_work,external_work,contact_work_normal,contact_work_friction,"
             "energy_balance_error,critical_step,contact_force,contact_force_x,contact_force_y,contact_force_z,contact_normal_force,"
             "contact_area,peak_pressure,peak_pressure_x,peak_pressure_y,peak_pressure_z,contact_nodes,stick_nodes,slip_nodes,"
             "uzawa_iterations\n";
  history << std::setprecision(17);
  std::size_t next_out = 0;

  const std::size_t history_every =
      sc.run.history_every > 0 ? static_cast<std::size_t>(sc.run.history_every) : std::max<std::size_t>(1, static_cast<std::size_t>(est_steps / 2000));
  Progress progress("solve", static_cast<std::size_t>(est_steps) + 1);

  RunSummary summary;
  summary.dt_min = std::numeric_limits<double>::infinity();
  summary.dt_max = 0;
  summary.von_mises_peak.assign(model.blocks.size(), 0.0);
  nlohmann::json failure = nullptr;
  struct ContactPeaks {
    double force = 0, force_time = 0, area = 0, area_time = 0, pressure = 0, pressure_time = 0;
    std::array<double, 3> pressure_at{0, 0, 0};
    std::size_t pressure_node = 0;
    int max_iterations = 0;
    std::size_t unconverged_steps = 0, contact_steps = 0;
  } peaks;
  auto current_position = [&](std::int32_t node) {
    std::array<double, 3> x{};
    for (int c = 0; c < 3; ++c) x[c] = model.X[3 * node + c] + solver.displacement()[3 * node + c];
    return x;
  };
  auto output = [&](const std::string& name, const std::vector<double>& u, const std::vector<double>& v, double t) {
    const std::vector<double> vm = write_state(model, staged.path() / "results" / name, u, v, &solver.contact());
    for (std::size_t b = 0; b < vm.size(); ++b) summary.von_mises_peak[b] = std::max(summary.von_mises_peak[b], vm[b]);
    pvd.emplace_back(t, "results/" + name);
    ++summary.outputs;
  };
  try {
    while (true) {
      check_interrupt();
      solver.advance_velocity();
      const Energies& en = solver.energies();
      const double t = solver.time();
      summary.max_relative_balance_error = std::max(summary.max_relative_balance_error, std::abs(en.balance_error()) / en.scale());
      const ContactStepReport& cr = solver.contact_report();
      std::array<double, 3> peak_at{0, 0, 0};
      if (cr.peak_node >= 0) peak_at = current_position(cr.peak_node);
      if (cr.active > 0) {
        ++peaks.contact_steps;
        const double force = std::sqrt(cr.force[0] * cr.force[0] + cr.force[1] * cr.force[1] + cr.force[2] * cr.force[2]);
        if (force > peaks.force) peaks.force = force, peaks.force_time = t;
        if (cr.area > peaks.area) peaks.area = cr.area, peaks.area_time = t;
        if (cr.peak_pressure > peaks.pressure)
          peaks.pressure = cr.peak_pressure, peaks.pressure_time = t, peaks.pressure_at = peak_at,
          peaks.pressure_node = static_cast<std::size_t>(cr.peak_node);
      }
      peaks.max_iterations = std::max(peaks.max_iterations, cr.iterations);
      if (!cr.converged) {
        if (peaks.unconverged_steps == 0) {
          std::ostringstream w;
          w << "contact: Uzawa iterations stopped at contact_solver.max_iterations = " << sc.contact_solver.max_iterations
            << " with residual " << cr.residual << " at step " << solver.step_index() << " (reported once; count in run.json)";
          log::warn(w.str());
        }
        ++peaks.unconverged_steps;
      }
      const bool scheduled = next_out < schedule.size() && t == schedule[next_out];
      if (solver.step_index() % history_every == 0 || scheduled || solver.finished()) {
        const double force = std::sqrt(cr.force[0] * cr.force[0] + cr.force[1] * cr.force[1] + cr.force[2] * cr.force[2]);
        history << solver.step_index() << ',' << t << ',' << solver.last_step() << ',' << en.kinetic << ',' << en.internal << ','
                << en.damping_work << ',' << en.external_work << ',' << en.contact_normal_work << ',' << en.contact_friction_work << ','
                << en.balance_error() << ',' << solver.critical_step() << ',' << force << ',' << cr.force[0] << ',' << cr.force[1]
                << ',' << cr.force[2] << ',' << cr.normal_force << ',' << cr.area << ',' << cr.peak_pressure << ',' << peak_at[0]
                << ',' << peak_at[1] << ',' << peak_at[2] << ',' << cr.active << ',' << cr.sticking << ',' << cr.slipping << ','
                << cr.iterations << '\n';
      }
      solver.check_energy();
      if (scheduled) {  // the solver lands on every scheduled time exactly
        std::ostringstream name;
        name << "state_" << std::setw(4) << std::setfill('0') << next_out << ".vtu";
        output(name.str(), solver.displacement(), solver.velocity_at_step(), t);
        ++next_out;
      }
      if (solver.finished()) break;
      solver.advance_position();
      summary.dt_min = std::min(summary.dt_min, solver.last_step());
      summary.dt_max = std::max(summary.dt_max, solver.last_step());
      if (progress.due()) {
        std::ostringstream note;
        note << "t=" << solver.time() << " s dt=" << solver.time_step();
        progress.update(solver.step_index(), note.str());
      }
    }
    summary.status = "completed";
  } catch (const NumericalError& e) {
    summary.status = "failed";
    failure = e.what();
    // The last good state: u^{n-1} (before the failing update), with the half-step velocity.
    output("last_good_state.vtu", solver.previous_displacement(), solver.half_step_velocity(),
           solver.time() - 0.5 * solver.time_step());
  }
  progress.finish();
  history.close();
  summary.steps = solver.step_index();
  summary.end_time = solver.time();
  summary.energy_balance_error = solver.energies().balance_error();
  summary.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  if (summary.steps == 0) summary.dt_min = summary.dt_max = 0;
  const std::size_t states_written = summary.status == "completed" ? summary.outputs : next_out;
  if (summary.status == "completed" && states_written != schedule.size()) {
    summary.status = "failed";
    failure = "wrote " + std::to_string(states_written) + " of the " + std::to_string(schedule.size()) + " scheduled states";
  }
  write_pvd(staged.path() / "results.pvd", pvd);

  const Energies& en = solver.energies();
  nlohmann::json j;
  j["tactus_version"] = kVersion;
  j["scenario"] = sc.file.string();
  j["status"] = summary.status;
  j["message"] = failure;
  j["units"] = "SI (m, kg, s, Pa, J)";
  // Names behind the "material" and "body" cell fields of the results (their values index these).
  j["materials"] = nlohmann::json::array();
  for (const auto& b : model.blocks) j["materials"].push_back(b.name);
  j["bodies"] = nlohmann::json::array();
  for (const auto& b : model.bodies) j["bodies"].push_back(b.name);
  j["nodes"] = model.num_nodes;
  j["tets"] = model.num_elements;
  j["threads"] = solver.threads();
  j["steps"] = summary.steps;
  j["end_time"] = summary.end_time;
  j["output_times"] = schedule;
  j["time_step"] = {{"min", summary.dt_min}, {"max", summary.dt_max}, {"safety", sc.run.time_step_safety},
                    {"min_ratio_to_nominal", solver.min_step_ratio()}, {"critical_initial", solver.initial_critical_step()},
                    {"critical_at_end", solver.critical_step()}, {"limit", solver.describe_step_limit()}};
  j["wall_time_s"] = summary.wall_seconds;
  j["timing_s"] = {{"stress_passes", solver.stress_seconds()}, {"contact", solver.contact_seconds()},
                   {"rest", summary.wall_seconds - solver.stress_seconds() - solver.contact_seconds()}};
  j["energy"] = {{"initial", en.initial}, {"kinetic", en.kinetic}, {"internal", en.internal}, {"damping_work", en.damping_work},
                 {"external_work", en.external_work}, {"contact_work_normal", en.contact_normal_work},
                 {"contact_work_friction", en.contact_friction_work}, {"balance_error", en.balance_error()},
                 {"balance_error_relative", std::abs(en.balance_error()) / en.scale()},
                 {"max_balance_error_relative", summary.max_relative_balance_error}};
  j["outputs"] = summary.outputs;
  nlohmann::json vm = nlohmann::json::object();
  for (std::size_t b = 0; b < model.blocks.size(); ++b) vm[model.blocks[b].name] = summary.von_mises_peak[b];
  j["peak_von_mises_at_outputs"] = vm;
  if (!model.contact_pairs.empty()) {
    nlohmann::json pairs = nlohmann::json::array();
    for (const auto& p : model.contact_pairs)
      pairs.push_back({{"name", p.name}, {"friction", p.friction}, {"slave_nodes", p.slave_nodes.size()},
                       {"master_triangles", p.master_triangles.size() / 3}, {"rigid_plane", p.rigid_plane}});
    const std::size_t peak_input_node = model.input_node(peaks.pressure_node);
    j["contact"] = {{"pairs", pairs},
                    {"steps_in_contact", peaks.contact_steps},
                    {"peak_force", {{"value", peaks.force}, {"time", peaks.force_time}}},
                    {"peak_area", {{"value", peaks.area}, {"time", peaks.area_time}}},
                    {"peak_pressure",
                     {{"value", peaks.pressure}, {"time", peaks.pressure_time}, {"position", peaks.pressure_at},
                      {"node", peaks.contact_steps ? nlohmann::json(peak_input_node + 1) : nlohmann::json(nullptr)}}},
                    {"uzawa", {{"tolerance", sc.contact_solver.tolerance}, {"max_iterations_used", peaks.max_iterations},
                               {"unconverged_steps", peaks.unconverged_steps}}}};
  }
  std::ofstream(staged.path() / "run.json") << j.dump(2) << '\n';
  staged.commit();
  log::info() << summary.status << ": " << summary.steps << " steps to t = " << summary.end_time << " s in "
              << summary.wall_seconds << " s; energy balance error " << std::abs(en.balance_error()) / en.scale() * 100
              << " % of the largest energy; " << summary.outputs << " states; results in " << output_dir.string();
  summary.run_json = j;
  if (summary.status == "failed")
    throw NumericalError(failure.get<std::string>() + " (last good state and history written to " + output_dir.string() + ")");
  return summary;
}

}  // namespace tactus::solver
