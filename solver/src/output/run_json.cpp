// run.json: the run's facts and figures, with the keys of core/contracts.hpp.
#include <algorithm>
#include <cmath>

#include "results.hpp"
#include "tactus/core/contracts.hpp"
#include "tactus/core/version.hpp"
#include "tactus/solver/run.hpp"

namespace tactus::solver {

namespace {

nlohmann::json contact_json(const Scenario& sc, const Model& model, const RunPeaks& peaks, double solver_window,
                            const ContactSolver::SearchCounts& search) {
  nlohmann::json pairs = nlohmann::json::array();
  for (std::size_t k = 0; k < model.contact_pairs.size(); ++k) {
    const ContactPair& p = model.contact_pairs[k];
    const RunPeaks::PairPeaks q = k < peaks.pairs.size() ? peaks.pairs[k] : RunPeaks::PairPeaks{};
    pairs.push_back({{"name", p.name},
                     {"friction", p.friction},
                     {"slave_nodes", p.slave_nodes.size()},
                     {"master", p.master->describe()},
                     {"peak_force", {{"value", q.force}, {"time", q.force_time}, {"normal_force_then", q.normal_force}}},
                     {"peak_area", {{"value", q.area}, {"time", q.area_time}}},
                     {"peak_pressure", {{"value", q.pressure}, {"time", q.pressure_time}}}});
  }
  const std::size_t peak_input_node = model.input_node(peaks.pressure_node);
  nlohmann::json at_outputs = nlohmann::json::array();
  for (const RunPeaks::AtOutput& o : peaks.at_outputs)
    at_outputs.push_back({{"time", o.time},
                          {"normal_force", o.normal_force},
                          {"area", o.area},
                          {"windowed_normal_force", o.windowed_normal_force},
                          {"windowed_area", o.windowed_area},
                          {"peak_pressure", o.peak_pressure},
                          {"averaged_peak_pressure", o.averaged_peak_pressure},
                          {"averaged_at", o.averaged_at}});
  return {{"pairs", pairs},
          {"steps_in_contact", peaks.contact_steps},
          {"peak_force", {{"value", peaks.force}, {"time", peaks.force_time}}},
          {"peak_area", {{"value", peaks.area}, {"time", peaks.area_time}}},
          {"peak_pressure",
           {{"value", peaks.pressure},
            {"time", peaks.pressure_time},
            {"position", peaks.pressure_at},
            {"node", peaks.contact_steps ? nlohmann::json(peak_input_node + 1) : nlohmann::json(nullptr)}}},
          {"peak_step_pressure", {{"value", peaks.step_pressure}, {"time", peaks.step_pressure_time}}},
          {"pressure_window", solver_window},
          {"pressure_average_area", sc.contact_solver.pressure_average_area},
          {"at_outputs", at_outputs},
          {"search", {{"verlet_skin", sc.contact_solver.verlet_skin}, {"searches", search.searches}, {"list_builds", search.builds}}},
          {"uzawa",
           {{"tolerance", sc.contact_solver.tolerance},
            {"max_iterations_used", peaks.max_iterations},
            {"unconverged_steps", peaks.unconverged_steps},
            {"recovering_rows", peaks.recovering_rows},
            {"sweep_blocks", sc.contact_solver.sweep_blocks},
            // the share of the rows swept in order (between the blocks, or in steps with too few rows to cut)
            {"rows_in_order", peaks.rows_swept ? static_cast<double>(peaks.rows_in_order) / static_cast<double>(peaks.rows_swept) : 0.0},
            {"recovery_speed", sc.contact_solver.recovery_speed}}}};
}

}  // namespace

void RunPeaks::add_reactions(const Reactions& r, double t) {
  const std::size_t n = r.force.size() / 3;
  if (reaction_peak.size() != n) reaction_peak.assign(n, 0.0), reaction_peak_time.assign(n, 0.0), reaction_peak_force.assign(3 * n, 0.0);
  for (std::size_t b = 0; b < n; ++b) {
    const double* f = &r.force[3 * b];
    const double mag = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    if (mag > reaction_peak[b]) {
      reaction_peak[b] = mag, reaction_peak_time[b] = t;
      std::copy(f, f + 3, &reaction_peak_force[3 * b]);
    }
  }
}

namespace {

// One entry per [[boundary]]: its reaction at the end and its peak (history.csv has every row).
nlohmann::json reactions_json(const Model& model, const ExplicitSolver& solver, const RunPeaks& peaks) {
  nlohmann::json out = nlohmann::json::array();
  const Reactions& r = solver.reactions();
  for (std::size_t b = 0; b < model.boundaries.size(); ++b) {
    auto vec = [](const std::vector<double>& v, std::size_t b3) {
      return std::vector<double>(v.begin() + static_cast<std::ptrdiff_t>(b3), v.begin() + static_cast<std::ptrdiff_t>(b3 + 3));
    };
    nlohmann::json e = {{"name", model.boundaries[b].name},
                        {"moment_about", model.boundaries[b].moment_about},
                        {"final_force", vec(r.force, 3 * b)},
                        {"final_moment", vec(r.moment, 3 * b)}};
    if (b < peaks.reaction_peak.size())
      e["peak_force"] = {{"value", peaks.reaction_peak[b]}, {"time", peaks.reaction_peak_time[b]}, {"vector", vec(peaks.reaction_peak_force, 3 * b)}};
    out.push_back(e);
  }
  return out;
}

// The joints' final angles and how each was driven; the grasp's grip and how quasi-static its
// hold was (kinetic / strain energy, flagged above 5 %).
// The handle's load per region and per digit at the end, with each one's share of the grip.
nlohmann::json regions_json(const Scenario& sc, const Model& model, const ExplicitSolver& solver, const GripRegions& g) {
  const std::vector<double> averaged = g.averaged_peak_pressure(model, solver.displacement().data(), sc.contact_solver.pressure_average_area);
  double total = 0;
  for (double f : g.force()) total += f;
  auto share = [&](double f) { return total > 0 ? f / total : 0.0; };
  nlohmann::json regions = nlohmann::json::array(), digits = nlohmann::json::array();
  for (std::size_t r = 0; r < g.names().size(); ++r)
    regions.push_back({{"name", g.names()[r]},
                       {"digit", g.digits()[g.digit()[r]]},
                       {"normal_force", g.force()[r]},
                       {"share", share(g.force()[r])},
                       {"area", g.area()[r]},
                       {"peak_pressure", g.peak_pressure()[r]},
                       {"averaged_peak_pressure", averaged[r]}});
  for (std::size_t d = 0; d < g.digits().size(); ++d)
    digits.push_back({{"name", g.digits()[d]}, {"normal_force", g.digit_force()[d]}, {"share", share(g.digit_force()[d])}});
  return {{"regions", regions}, {"digits", digits}, {"pressure_average_area", sc.contact_solver.pressure_average_area}};
}

nlohmann::json joints_json(const Scenario& sc, const Model& model, const ExplicitSolver& solver, const JointDrive& drive) {
  nlohmann::json joints = nlohmann::json::array();
  for (std::size_t j = 0; j < drive.skeleton().joints.size(); ++j) {
    const bool torque = drive.torque_driven(j);
    const bool by_angle =
        std::any_of(sc.joints.begin(), sc.joints.end(), [&](const JointSpec& s) { return s.name == drive.skeleton().joints[j].name; });
    joints.push_back({{"name", drive.skeleton().joints[j].name},
                      {"driven_by", by_angle ? "angle"
                                    : torque ? "torque"
                                             : "held"},
                      {"final_flexion_deg", drive.flexion_at_step()[j] * 180 / M_PI},
                      {"final_torque", torque ? drive.torque(j) : 0.0}});
  }
  nlohmann::json out = {{"skeleton", sc.skeleton->file.string()}, {"body", sc.skeleton->body}, {"joints", joints}};
  if (drive.grasp()) {
    const double ratio = drive.max_kinetic_ratio_in_hold();
    out["grasp"] = {{"handle", sc.grasp.handle},
                    {"target_force", sc.grasp.target_force},
                    {"final_grip_force", drive.grip_force()},
                    {"final_grip_error_relative", (drive.grip_force() - sc.grasp.target_force) / sc.grasp.target_force},
                    {"final_drive", drive.drive_scale()},
                    {"max_kinetic_to_strain_energy_in_hold", ratio},
                    {"quasi_static", ratio <= 0.05},
                    {"hold_from", sc.grasp.ramp_time}};
    if (const GripRegions* g = solver.grip_regions()) out["grasp"]["regions"] = regions_json(sc, model, solver, *g);
  }
  return out;
}

// Dynamic relaxation (relaxation.hpp): whether and when the run relaxed, and the last residual and damping.
nlohmann::json relaxation_json(const Scenario& sc, const ExplicitSolver& solver, const RunSummary& summary) {
  const Relaxation& r = solver.relaxation();
  return {{"adaptive", sc.damping.adaptive},
          {"residual_tolerance", sc.damping.residual_tolerance},
          {"relaxed", summary.relaxed_at >= 0},
          {"relaxed_at", summary.relaxed_at >= 0 ? nlohmann::json(summary.relaxed_at) : nlohmann::json(nullptr)},
          {"final_relative_residual", r.relative_residual()},
          {"final_alpha", r.alpha()},
          {"final_omega", r.omega()}};
}

// Names behind the "material" cell field of the results (its values index them), with each
// block's formulation and, for ANP blocks, its pressure smoothing and volume floor.
void add_materials(const Model& model, nlohmann::json& j) {
  namespace k = contracts::run_json;
  j[k::materials] = nlohmann::json::array();
  j[k::formulations] = j[k::pressure_smoothing] = j[k::volume_floor] = nlohmann::json::object();
  for (const auto& b : model.blocks) {
    j[k::materials].push_back(b.name);
    j[k::formulations][b.name] = b.material.anp() ? "anp" : "standard";
    if (!b.material.anp()) continue;
    j[k::pressure_smoothing][b.name] = b.material.pressure_smoothing();
    j[k::volume_floor][b.name] = b.material.volume_floor();
  }
}

}  // namespace

nlohmann::json run_json(const Scenario& sc, const Model& model, const ExplicitSolver& solver, const RunSummary& summary, const RunPeaks& peaks,
                        const nlohmann::json& failure) {
  namespace k = contracts::run_json;
  const Energies& en = solver.energies();
  nlohmann::json j;
  j["tactus_version"] = kVersion;
  j["scenario"] = sc.file.string();
  j["scenario_overrides"] = sc.overrides;  // tactus-solve --set, in order
  j[k::status] = summary.status;
  j[k::message] = failure;
  if (sc.damping.adaptive || sc.damping.residual_tolerance > 0) j["relaxation"] = relaxation_json(sc, solver, summary);
  j["units"] = "SI (m, kg, s, Pa, J)";
  add_materials(model, j);
  j[k::bodies] = nlohmann::json::array();
  for (const auto& b : model.bodies) j[k::bodies].push_back(b.name);
  j[k::nodes] = model.num_nodes;
  j[k::tets] = model.num_elements;
  j["threads"] = solver.threads();
  if (sc.run.checkpoints() || !summary.restarts.empty()) {
    nlohmann::json from = nlohmann::json::array();
    for (const auto& [step, time] : summary.restarts) from.push_back({{"step", step}, {"time", time}});
    j["checkpoints"] = {{"interval", sc.run.checkpoint_interval}, {"wall_interval", sc.run.checkpoint_wall_interval}, {"restarted_from", from}};
  }
  j[k::steps] = summary.steps;
  j[k::end_time] = summary.end_time;
  j[k::output_times] = solver.schedule();
  j[k::time_step] = {{"min", summary.dt_min},
                     {"max", summary.dt_max},
                     {"safety", sc.run.time_step_safety},
                     {"min_ratio_to_nominal", solver.min_step_ratio()},
                     {"critical_initial", solver.initial_critical_step()},
                     {"critical_at_end", solver.critical_step()},
                     {"limit", solver.describe_step_limit()}};
  j[k::wall_time] = summary.wall_seconds;
  j[k::timing] = {{"stress_passes", solver.stress_seconds()},
                  {"contact", solver.contact_seconds()},
                  {"rest", summary.wall_seconds - solver.stress_seconds() - solver.contact_seconds()},
                  // of stress_passes: the next steps' contact detection, on one thread while the others computed forces
                  {"contact_detection_during_stress_passes", solver.detection_ahead_seconds()}};
  j[k::energy] = {{"initial", en.initial},
                  {"kinetic", en.kinetic},
                  {"internal", en.internal},
                  {"damping_work", en.damping_work},
                  {"external_work", en.external_work},
                  {"contact_work_normal", en.contact_normal_work},
                  {"contact_work_friction", en.contact_friction_work},
                  {"added_mass_kinetic", en.added_mass_kinetic},
                  {"balance_error", en.balance_error()},
                  {"balance_error_relative", std::abs(en.balance_error()) / en.scale()},
                  {"max_balance_error_relative", summary.max_relative_balance_error}};
  j[k::outputs] = summary.outputs;
  j[k::memory] = {{"model", model.memory_bytes()}, {"solver", solver.memory_bytes()}};
  nlohmann::json vm = nlohmann::json::object();
  for (std::size_t b = 0; b < model.blocks.size(); ++b) vm[model.blocks[b].name] = summary.von_mises_peak[b];
  j[k::peak_von_mises] = vm;
  if (!model.contact_pairs.empty())
    j[k::contact] = contact_json(sc, model, peaks, solver.contact().pressure_window(), solver.contact().search_counts());
  j[k::reactions] = reactions_json(model, solver, peaks);
  if (!solver.rigid_bodies().empty()) {
    nlohmann::json rigid = nlohmann::json::array();
    auto vec = [](const Vec3d& v) { return std::vector<double>{v[0], v[1], v[2]}; };
    for (const RigidBody& b : solver.rigid_bodies()) {
      nlohmann::json e = {{"name", b.name},
                          {"history_columns", rigid_column_name(b.name)},
                          {"nodes", b.nodes.size()},
                          {"mass", b.mass},
                          {"reference_centre", vec(b.centre0)},
                          {"principal_moments", vec(b.principal)},
                          {"prescribed", b.prescribed},
                          {"final_centre", vec(b.centre)},
                          {"final_rotation_vector", vec(b.rotation_vector())},
                          {"final_velocity", vec(b.momentum / b.mass)},
                          {"final_angular_velocity", vec(b.angular_velocity_of(b.angular_momentum))}};
      if (b.prescribed) e["final_reaction"] = {{"force", vec(b.reaction_force)}, {"moment", vec(b.reaction_moment)}};
      rigid.push_back(e);
    }
    j["rigid_bodies"] = rigid;
  }
  if (const JointDrive* drive = solver.joint_drive()) j["joints"] = joints_json(sc, model, solver, *drive);
  if (solver.mass_scaling()) {
    nlohmann::json bodies = nlohmann::json::object();
    for (std::size_t b = 0; b < model.bodies.size(); ++b)
      bodies[model.bodies[b].name] = {
          {"mass", solver.body_mass()[b]}, {"added_mass", solver.added_mass()[b]}, {"fraction", solver.added_mass()[b] / solver.body_mass()[b]}};
    const Vec3& p = solver.added_momentum();
    j[k::mass_scaling] = {{"minimum_time_step", sc.run.minimum_time_step},
                          {"added_mass_limit", sc.run.added_mass_limit},
                          {"bodies", bodies},
                          {"added_kinetic_energy", en.added_mass_kinetic},
                          {"added_momentum", {p[0], p[1], p[2]}}};
  }
  return j;
}

}  // namespace tactus::solver
