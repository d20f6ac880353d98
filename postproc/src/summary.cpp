// The report's numbers from the states, the history and run.json.
#include "tactus/postproc/summary.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tactus/core/contracts.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/mesh.hpp"

namespace tactus::postproc {

namespace rk = contracts::run_json;
namespace hc = contracts::history;
namespace cc = contracts::cell;
namespace cp = contracts::point;

namespace {

std::array<double, 3> centroid(const TetMesh& m, std::size_t e) {
  std::array<double, 3> c{0, 0, 0};
  for (int v : m.tets[e])
    for (int d = 0; d < 3; ++d) c[d] += 0.25 * m.nodes[static_cast<std::size_t>(v)][d];
  return c;
}

const MeshField& need_cell(const VtuContents& v, const std::string& name, const std::string& file) {
  const MeshField* f = v.cell_field(name);
  if (!f) throw InputError(file, name, "cell data " + name + " (a tactus-solve state)", "missing");
  return *f;
}

nlohmann::json peak_json(const PeakAt& p, const char* unit) {
  nlohmann::json j = {{"value", p.value}, {"unit", unit}, {"time_s", p.time}, {"position_m", p.position}, {"index", p.index}};
  if (!p.body.empty()) j["body"] = p.body;
  return j;
}

// The body (run.json name) of the cells around a node: the body a contact pressure acts on.
std::string body_of_node(const VtuContents& v, std::size_t node, const std::vector<std::string>& bodies, const std::string& file) {
  const MeshField* body = v.cell_field(cc::body.name);
  if (!body) return "";
  for (std::size_t e = 0; e < v.mesh.tets.size(); ++e)
    for (int k : v.mesh.tets[e])
      if (static_cast<std::size_t>(k) == node) {
        const auto b = static_cast<std::size_t>(body->values[e]);
        if (body->values[e] < 0 || b >= bodies.size())
          throw InputError(file, cc::body.name, "indices below " + std::to_string(bodies.size()) + " (run.json bodies)",
                           std::to_string(body->values[e]));
        return bodies[b];
      }
  return "";
}

}  // namespace

namespace {

double number_at(const nlohmann::json& node, const char* key) { return node.contains(key) && node[key].is_number() ? node[key].get<double>() : 0.0; }

// The run's figures from run.json: status, sizes, steps, timing, energies, mass scaling.
void read_run_figures(const nlohmann::json& j, Summary& s) {
  const auto num = number_at;
  s.status = j.value(rk::status, "");
  if (j.contains(rk::message) && j[rk::message].is_string()) s.message = j[rk::message].get<std::string>();
  s.steps = j.value(rk::steps, std::size_t{0});
  s.nodes = j.value(rk::nodes, std::size_t{0});
  s.tets = j.value(rk::tets, std::size_t{0});
  s.end_time = num(j, rk::end_time);
  s.wall_time = num(j, rk::wall_time);
  if (j.contains(rk::time_step)) s.dt_min = num(j[rk::time_step], "min"), s.dt_max = num(j[rk::time_step], "max");
  if (j.contains(rk::timing)) s.stress_seconds = num(j[rk::timing], "stress_passes"), s.contact_seconds = num(j[rk::timing], "contact");
  if (j.contains(rk::energy)) {
    const auto& e = j[rk::energy];
    s.initial_energy = num(e, "initial"), s.balance_error = num(e, "balance_error");
    s.contact_work_normal = num(e, "contact_work_normal"), s.contact_work_friction = num(e, "contact_work_friction");
  }
  if (j.contains(rk::mass_scaling) && j[rk::mass_scaling].is_object()) {
    const auto& ms = j[rk::mass_scaling];
    s.minimum_time_step = num(ms, "minimum_time_step");
    if (ms.contains("bodies") && ms["bodies"].is_object())
      for (const auto& [body, v] : ms["bodies"].items()) s.added_mass.push_back({body, num(v, "added_mass"), num(v, "fraction")});
  }
}

// The contact figures of run.json, which hold every step's peaks (history rows are every few steps).
void read_contact_figures(const nlohmann::json& j, Summary& s) {
  const auto num = number_at;
  if (j.contains(rk::contact)) {
    const auto& c = j[rk::contact];
    if (c.contains("peak_pressure")) {
      const auto& p = c["peak_pressure"];
      s.peak_pressure_steps.value = num(p, "value"), s.peak_pressure_steps.time = num(p, "time");
      if (p.contains("position")) s.peak_pressure_steps.position = p["position"].get<std::array<double, 3>>();
      if (p.contains("node") && p["node"].is_number()) s.peak_pressure_steps.index = p["node"].get<long>();
    }
    if (c.contains("peak_area")) s.largest_area.value = num(c["peak_area"], "value"), s.largest_area.time = num(c["peak_area"], "time");
    if (c.contains("peak_force")) s.peak_force.value = num(c["peak_force"], "value"), s.peak_force.time = num(c["peak_force"], "time");
    s.contact_occurred = c.value("steps_in_contact", std::size_t{0}) > 0;
    if (c.contains("pairs") && c["pairs"].is_array())
      for (const auto& p : c["pairs"]) {
        if (!p.is_object() || !p.contains("peak_force")) continue;
        s.contact_pairs.push_back({p.value("name", ""), num(p["peak_force"], "value"), num(p["peak_force"], "time"),
                                   p.contains("peak_area") ? num(p["peak_area"], "value") : 0.0,
                                   p.contains("peak_pressure") ? num(p["peak_pressure"], "value") : 0.0});
      }
  }
}

// The grasp of run.json (joints.grasp): grip, hold and the regions' shares.
void read_grasp(const nlohmann::json& j, Summary& s) {
  const auto num = number_at;
  if (!j.contains("joints") || !j["joints"].is_object() || !j["joints"].contains("grasp")) return;
  const auto& g = j["joints"]["grasp"];
  Summary::Grasp& out = s.grasp;
  out.on = true;
  out.handle = g.value("handle", "");
  out.target = num(g, "target_force"), out.final_grip = num(g, "final_grip_force");
  out.max_kinetic_ratio = num(g, "max_kinetic_to_strain_energy_in_hold"), out.hold_from = num(g, "hold_from");
  out.quasi_static = g.value("quasi_static", true);
  if (!g.contains("regions") || !g["regions"].is_object()) return;
  const auto& r = g["regions"];
  out.sensor_area = num(r, "pressure_average_area");
  for (const char* list : {"regions", "digits"})
    if (r.contains(list) && r[list].is_array())
      for (const auto& e : r[list]) {
        Summary::GripShare share{e.value("name", ""), e.value("digit", ""), num(e, "normal_force"), num(e, "share"), 0, 0, 0};
        if (e.contains("area")) share.area = num(e, "area"), share.peak_pressure = num(e, "peak_pressure");
        if (e.contains("averaged_peak_pressure")) share.averaged_peak_pressure = num(e, "averaged_peak_pressure");
        (std::string(list) == "regions" ? out.regions : out.digits).push_back(share);
      }
}

// The supports' reactions of run.json.
void read_reactions(const nlohmann::json& j, Summary& s) {
  const auto num = number_at;
  if (j.contains(rk::reactions) && j[rk::reactions].is_array())
    for (const auto& e : j[rk::reactions]) {
      ReactionSummary rs;
      rs.name = e.value("name", "");
      auto vec3 = [](const nlohmann::json& v) {
        return v.is_array() && v.size() == 3 ? v.get<std::array<double, 3>>() : std::array<double, 3>{0, 0, 0};
      };
      if (e.contains("final_force")) rs.final_force = vec3(e["final_force"]);
      if (e.contains("final_moment")) rs.final_moment = vec3(e["final_moment"]);
      if (e.contains("peak_force")) {
        rs.peak = num(e["peak_force"], "value"), rs.peak_time = num(e["peak_force"], "time");
        if (e["peak_force"].contains("vector")) rs.peak_force = vec3(e["peak_force"]["vector"]);
      }
      s.reactions.push_back(rs);
    }
}

// The largest isochoric fibre stretch of state v (time t) so far, with the von Mises stress of
// the fibre stress there.
void track_fibre_stretch(const VtuContents& v, double t, Summary& s) {
  const MeshField* fs2 = v.cell_field("fibre_stretch_isochoric");
  if (!fs2 || fs2->components != 2) return;
  const MeshField* stress = v.cell_field("fibre_stress");
  for (std::size_t e = 0; 2 * e + 1 < fs2->values.size(); ++e)
    for (int k = 0; k < 2; ++k)
      if (fs2->values[2 * e + k] > s.fibre_stretch.value) {
        s.fibre_stretch = {fs2->values[2 * e + k], t, centroid(v.mesh, e), static_cast<long>(e) + 1, ""};
        s.fibre_family = k + 1;
        s.fibre_stress_there = 0;
        if (stress && stress->components == 6) {
          const double* q = &stress->values[6 * e];
          const double a = q[0] - q[1], b = q[1] - q[2], c = q[2] - q[0];
          s.fibre_stress_there = std::sqrt(0.5 * (a * a + b * b + c * c) + 3.0 * (q[3] * q[3] + q[4] * q[4] + q[5] * q[5]));
        }
      }
}

// One output state's figures (its per-material peaks, contact nodes and pressure, the contact
// force of the nearest history row), and the run's peaks over the states so far.
FrameSummary summarize_frame(const Results& r, const Frame& f, std::size_t M, Summary& s) {
  const History& h = r.history;
  const VtuContents v = read_vtu(f.file);
  const std::string file = f.file.string();
  // A state of another model (a file copied in, or a folder mixed from two runs) would be
  // reported as this run's: its size must be the run's.
  if ((s.nodes && v.mesh.nodes.size() != s.nodes) || (s.tets && v.mesh.tets.size() != s.tets))
    throw InputError(file, "", "a state of this run's model (" + std::to_string(s.nodes) + " nodes, " + std::to_string(s.tets) + " tets, run.json)",
                     std::to_string(v.mesh.nodes.size()) + " nodes, " + std::to_string(v.mesh.tets.size()) + " tets: a state of another model");
  const MeshField& vm = need_cell(v, cc::von_mises.name, file);
  const MeshField& mat = need_cell(v, cc::material.name, file);
  FrameSummary fs;
  fs.time = f.time;
  fs.file = f.file.filename().string();
  fs.von_mises_max.assign(M, 0.0);
  for (std::size_t e = 0; e < vm.values.size(); ++e) {
    const std::size_t m = static_cast<std::size_t>(mat.values[e]);
    if (m >= M) throw InputError(file, "material", "indices below " + std::to_string(M) + " (run.json materials)", std::to_string(m));
    if (vm.values[e] > fs.von_mises_max[m]) fs.von_mises_max[m] = vm.values[e];
    if (vm.values[e] > s.von_mises[m].von_mises.value) {
      s.von_mises[m].von_mises = {vm.values[e], f.time, centroid(v.mesh, e), static_cast<long>(e) + 1, ""};
    }
  }
  track_fibre_stretch(v, f.time, s);
  if (const MeshField* p = v.point_field(cp::contact_pressure.name)) {
    bool new_peak = false;  // in this state (possibly at the same node as before: its body is looked up again)
    for (std::size_t i = 0; i < p->values.size(); ++i) {
      const double pi = p->values[i];
      if (pi > 0) ++fs.contact_nodes;
      if (pi > fs.contact_pressure_max) fs.contact_pressure_max = pi;
      if (pi > s.peak_pressure_outputs.value) {
        s.peak_pressure_outputs = {pi, f.time, {v.mesh.nodes[i][0], v.mesh.nodes[i][1], v.mesh.nodes[i][2]}, static_cast<long>(i) + 1, ""};
        new_peak = true;
      }
    }
    if (new_peak) s.peak_pressure_outputs.body = body_of_node(v, static_cast<std::size_t>(s.peak_pressure_outputs.index - 1), r.bodies, file);
  }
  if (h.has(hc::contact_force.name) && h.rows() > 0) {  // nearest history row
    const auto& t = h.column(hc::time.name);
    const std::size_t k = static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), f.time - 1e-15) - t.begin());
    fs.contact_force = h.column(hc::contact_force.name)[std::min(k, t.size() - 1)];
  }
  return fs;
}

}  // namespace

Summary summarize(const Results& r) {
  Summary s;
  const auto j = nlohmann::json::parse(r.run_json);
  read_run_figures(j, s);
  const History& h = r.history;
  if (h.has(hc::kinetic_energy.name) && h.rows() > 0) s.initial_kinetic = h.column(hc::kinetic_energy.name).front();
  read_contact_figures(j, s);
  read_reactions(j, s);
  read_grasp(j, s);
  const std::size_t M = std::max<std::size_t>(r.materials.size(), 1);
  s.von_mises.resize(M);
  for (std::size_t m = 0; m < M; ++m) s.von_mises[m].material = m < r.materials.size() ? r.materials[m] : "material " + std::to_string(m);
  for (const Frame& f : r.frames) s.frames.push_back(summarize_frame(r, f, M, s));
  s.missing = r.missing;
  return s;
}

std::string summary_json(const Summary& s) {
  nlohmann::json j;
  j["run"] = {{"status", s.status},
              {"message", s.message},
              {"steps", s.steps},
              {"nodes", s.nodes},
              {"tets", s.tets},
              {"end_time_s", s.end_time},
              {"dt_min_s", s.dt_min},
              {"dt_max_s", s.dt_max},
              {"wall_time_s", s.wall_time},
              {"stress_pass_s", s.stress_seconds},
              {"contact_s", s.contact_seconds}};
  j["energy"] = {{"initial_J", s.initial_energy},
                 {"initial_kinetic_J", s.initial_kinetic},
                 {"balance_error_J", s.balance_error},
                 {"balance_error_of_initial_kinetic", s.initial_kinetic > 0 ? std::abs(s.balance_error) / s.initial_kinetic : 0.0},
                 {"contact_work_normal_J", s.contact_work_normal},
                 {"frictional_dissipation_J", s.contact_work_friction}};
  nlohmann::json vm = nlohmann::json::object();
  for (const auto& m : s.von_mises) vm[m.material] = peak_json(m.von_mises, "Pa");
  j["peak_von_mises"] = vm;
  if (s.fibre_stretch.value > 0) {
    j["largest_fibre_stretch"] = peak_json(s.fibre_stretch, "");
    j["largest_fibre_stretch"]["family"] = s.fibre_family;
    j["largest_fibre_stretch"]["fibre_stress_von_mises_Pa"] = s.fibre_stress_there;
  }
  if (s.minimum_time_step > 0) {
    j["mass_scaling"] = {{"minimum_time_step_s", s.minimum_time_step}, {"bodies", nlohmann::json::object()}};
    for (const auto& a : s.added_mass) j["mass_scaling"]["bodies"][a.body] = {{"added_mass_kg", a.added}, {"fraction", a.fraction}};
  }
  if (s.grasp.on) {
    nlohmann::json shares = nlohmann::json::array();
    for (const auto& d : s.grasp.digits) shares.push_back({{"digit", d.name}, {"normal_force_N", d.force}, {"share", d.share}});
    j["grasp"] = {{"handle", s.grasp.handle},
                  {"target_force_N", s.grasp.target},
                  {"final_grip_N", s.grasp.final_grip},
                  {"max_kinetic_to_strain_energy_in_hold", s.grasp.max_kinetic_ratio},
                  {"quasi_static", s.grasp.quasi_static},
                  {"digits", shares}};
  }
  j["contact"] = {{"occurred", s.contact_occurred}};
  if (s.contact_occurred) {
    j["contact"]["peak_pressure_any_step"] = peak_json(s.peak_pressure_steps, "Pa");
    j["contact"]["peak_pressure_at_outputs"] = peak_json(s.peak_pressure_outputs, "Pa");
    j["contact"]["largest_area"] = {{"value", s.largest_area.value}, {"unit", "m^2"}, {"time_s", s.largest_area.time}};
    j["contact"]["peak_force"] = {{"value", s.peak_force.value}, {"unit", "N"}, {"time_s", s.peak_force.time}};
  }
  nlohmann::json reactions = nlohmann::json::array();
  for (const auto& rs : s.reactions)
    reactions.push_back({{"name", rs.name},
                         {"peak_N", rs.peak},
                         {"peak_time_s", rs.peak_time},
                         {"peak_force_N", rs.peak_force},
                         {"final_force_N", rs.final_force},
                         {"final_moment_N_m", rs.final_moment}});
  j["reactions"] = reactions;
  nlohmann::json frames = nlohmann::json::array();
  for (const auto& f : s.frames) {
    nlohmann::json fv = nlohmann::json::object();
    for (std::size_t m = 0; m < f.von_mises_max.size(); ++m) fv[s.von_mises[m].material] = f.von_mises_max[m];
    frames.push_back({{"time_s", f.time},
                      {"file", f.file},
                      {"von_mises_max_Pa", fv},
                      {"contact_pressure_max_Pa", f.contact_pressure_max},
                      {"contact_nodes", f.contact_nodes},
                      {"contact_force_N", f.contact_force}});
  }
  j["outputs"] = frames;
  j["pictures"] = s.pictures;
  j["missing_states"] = s.missing;
  if (!s.interactive.empty()) j["interactive_report"] = s.interactive;
  return j.dump(2) + "\n";
}

// The grasp's section: the grip against its target, the hold, and each region's and digit's share.
void grasp_markdown(const Summary::Grasp& g, std::ostream& o) {
  o << "\n## Grasp\n\nGrip on '" << g.handle << "': " << g.final_grip << " N at the end against a target of " << g.target << " N ("
    << 100 * (g.final_grip - g.target) / g.target << " %). Hold from t = " << g.hold_from * 1e3 << " ms: largest kinetic / strain energy "
    << 100 * g.max_kinetic_ratio << " %, "
    << (g.quasi_static ? "quasi-static (at most 5 %)" : "**dynamic** (above 5 %: a longer ramp_time or more damping)") << ".\n";
  if (g.regions.empty()) return;
  o << "\n| digit | normal force (N) | share of the grip |\n|---|---|---|\n";
  for (const auto& d : g.digits) o << "| " << d.name << " | " << d.force << " | " << 100 * d.share << " % |\n";
  o << "\n| region | digit | normal force (N) | share | area (mm^2) | peak nodal pressure (MPa) | peak over " << g.sensor_area * 1e6
    << " mm^2 (MPa) |\n|---|---|---|---|---|---|---|\n";
  for (const auto& r : g.regions)
    o << "| " << r.name << " | " << r.digit << " | " << r.force << " | " << 100 * r.share << " % | " << r.area * 1e6 << " | " << r.peak_pressure / 1e6
      << " | " << r.averaged_peak_pressure / 1e6 << " |\n";
  o << "\nEach skin node the handle touches belongs to its nearest bone's segment, or, nearest a metacarpal or carpal, to a palm zone "
       "(thenar, central, hypothenar) by its nearest metacarpal (docs/design.md, \"Joints and the grasp\"). grip_map.png unrolls the "
       "pressure around the handle.\n";
}

std::string summary_markdown(const Summary& s) {
  std::ostringstream o;
  auto mm = [](const std::array<double, 3>& p) {
    std::ostringstream q;
    q << std::fixed << std::setprecision(1) << "(" << p[0] * 1e3 << ", " << p[1] * 1e3 << ", " << p[2] * 1e3 << ") mm";
    return q.str();
  };
  o << std::setprecision(4);
  o << "# tactus report\n\n";
  o << "Run " << s.status << (s.message.empty() ? "" : ": " + s.message) << ". " << s.steps << " steps to t = " << s.end_time * 1e3 << " ms, dt "
    << s.dt_min << " .. " << s.dt_max << " s, " << s.nodes << " nodes, " << s.tets << " tets; wall time " << s.wall_time << " s (stress passes "
    << s.stress_seconds << " s, contact " << s.contact_seconds << " s).\n\n";
  o << "Energy balance error " << s.balance_error << " J";
  if (s.initial_kinetic > 0)
    o << " (" << 100 * std::abs(s.balance_error) / s.initial_kinetic << " % of the initial kinetic energy " << s.initial_kinetic << " J)";
  o << "; contact work: normal " << s.contact_work_normal << " J, frictional dissipation " << s.contact_work_friction << " J.\n\n";
  if (s.minimum_time_step > 0) {
    o << "Mass scaling kept the step at or above " << s.minimum_time_step << " s, adding:";
    for (const auto& a : s.added_mass) o << " " << a.body << " " << a.added << " kg (" << 100 * a.fraction << " % of its mass);";
    o << " the added mass's kinetic energy is booked in the energy balance.\n\n";
  }
  o << "## Peak von Mises stress (over the output states)\n\n| material | peak (MPa) | time (ms) | where (element centroid) |\n|---|---|---|---|\n";
  for (const auto& m : s.von_mises) {
    // No tet of the material had any stress (rigid, a joint gap, or unloaded): no peak to place.
    if (m.von_mises.index < 0) {
      o << "| " << m.material << " | 0 | - | no stress in any output state (rigid, a joint gap placed by the bones, or unloaded) |\n";
      continue;
    }
    o << "| " << m.material << " | " << m.von_mises.value / 1e6 << " | " << m.von_mises.time * 1e3 << " | element " << m.von_mises.index << ", "
      << mm(m.von_mises.position) << " |\n";
  }
  if (s.fibre_stretch.value > 0)
    o << "\nLargest isochoric fibre stretch (sqrt(J4bar), hgo) over the output states: " << s.fibre_stretch.value << " (family " << s.fibre_family
      << ") at t = " << s.fibre_stretch.time * 1e3 << " ms, element " << s.fibre_stretch.index << ", " << mm(s.fibre_stretch.position)
      << "; the fibre terms' stress there: " << s.fibre_stress_there / 1e6 << " MPa von Mises.\n";
  o << "\n## Contact\n\n";
  if (!s.contact_occurred) {
    o << "No contact occurred during the run: no pressure map, zero contact force.\n";
  } else {
    o << "| quantity | value | time (ms) | where |\n|---|---|---|---|\n";
    o << "| peak pressure, output states | " << s.peak_pressure_outputs.value / 1e6 << " MPa | " << s.peak_pressure_outputs.time * 1e3 << " | node "
      << s.peak_pressure_outputs.index << (s.peak_pressure_outputs.body.empty() ? "" : " on " + s.peak_pressure_outputs.body) << ", "
      << mm(s.peak_pressure_outputs.position) << " |\n";
    o << "| peak pressure, any step | " << s.peak_pressure_steps.value / 1e6 << " MPa | " << s.peak_pressure_steps.time * 1e3 << " | node "
      << s.peak_pressure_steps.index << ", " << mm(s.peak_pressure_steps.position) << " |\n";
    o << "| largest contact area, one step | " << s.largest_area.value * 1e6 << " mm^2 | " << s.largest_area.time * 1e3 << " | |\n";
    o << "| peak contact force, one step | " << s.peak_force.value << " N | " << s.peak_force.time * 1e3 << " | |\n";
    o << "\nPressures are averaged over the run's pressure window (run.json contact.pressure_window), so a node's first-touch "
         "impulse shows as impulse / window rather than impulse / step; the output-state peak is what the pressure picture shows. "
         "The force and area above, and the pairs' figures below, are single steps' and carry those impulses (run.json "
         "contact.at_outputs has the force and area through the window at each output).\n";
    if (!s.contact_pairs.empty()) {
      o << "\n| contact pair | peak force on its slave nodes, one step (N) | at (ms) | largest area, one step (mm^2) | peak r_n / A, one "
           "step (MPa) |\n|---|---|---|---|---|\n";
      for (const auto& p : s.contact_pairs)
        o << "| " << p.name << " | " << p.force << " | " << p.force_time * 1e3 << " | " << p.area * 1e6 << " | " << p.pressure / 1e6 << " |\n";
    }
  }
  if (s.grasp.on) grasp_markdown(s.grasp, o);
  if (!s.reactions.empty()) {
    o << "\n## Support reactions\n\n| boundary | peak abs(R) (N) | at (ms) | R then (N) | R at the end (N) | moment at the end (N m) "
         "|\n|---|---|---|---|---|---|\n";
    auto v3 = [](const std::array<double, 3>& v) {
      std::ostringstream t;
      t << "(" << v[0] << ", " << v[1] << ", " << v[2] << ")";
      return t.str();
    };
    for (const auto& rs : s.reactions)
      o << "| " << rs.name << " | " << rs.peak << " | " << rs.peak_time * 1e3 << " | " << v3(rs.peak_force) << " | " << v3(rs.final_force) << " | "
        << v3(rs.final_moment) << " |\n";
    o << "\nThe force each support applies to the body (history.csv has it at every row, with its moment).\n";
  }
  if (!s.missing.empty()) {
    o << "\n**Missing output states** (listed in results.pvd, left out of this report):";
    for (const auto& m : s.missing) o << " " << m << ";";
    o << "\n";
  }
  o << "\n## Output states\n\n| t (ms) | file |";
  for (const auto& m : s.von_mises) o << " max von Mises " << m.material << " (MPa) |";
  o << " max pressure (MPa) | contact nodes | contact force (N) |\n|---|---|";
  for (std::size_t m = 0; m < s.von_mises.size(); ++m) o << "---|";
  o << "---|---|---|\n";
  for (const auto& f : s.frames) {
    o << "| " << f.time * 1e3 << " | " << f.file << " |";
    for (double v : f.von_mises_max) o << " " << v / 1e6 << " |";
    o << " " << f.contact_pressure_max / 1e6 << " | " << f.contact_nodes << " | " << f.contact_force << " |\n";
  }
  if (!s.interactive.empty())
    o << "\n## Interactive report\n\nOpen [" << s.interactive << "](" << s.interactive
      << ") in a browser (from the file system; no server needed): turn and zoom the bodies, scrub through the output states, switch between "
         "contact pressure, von Mises and displacement, and click a node to read its values.\n";
  if (!s.pictures.empty()) {
    o << "\n## Pictures\n\n";
    for (const auto& p : s.pictures) o << "![" << p << "](" << p << ")\n";
  }
  return o.str();
}

}  // namespace tactus::postproc
