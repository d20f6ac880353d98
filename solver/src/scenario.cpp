// scenario.toml reader. All validation is driven by the declarations below, which also produce
// the key reference (`tactus-solve keys`), so the docs cannot drift from what is accepted.
#include "tactus/solver/scenario.hpp"
#include "tactus/core/file_io.hpp"

#include <toml++/toml.h>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <optional>
#include <set>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/solver/material.hpp"

namespace fs = std::filesystem;

namespace tactus::solver {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

ValueSpec opt(ValueSpec s, std::string default_text) {
  s.required = false;
  s.default_text = std::move(default_text);
  return s;
}
// A count: an integer, or a float with no fractional part (1e7).
ValueSpec whole(ValueSpec s) {
  s.type = ValueType::integer;
  return s;
}
ValueSpec typed(std::string key, ValueType type, std::string unit, std::string doc, bool required, std::string default_text = {}) {
  ValueSpec s;
  s.key = std::move(key);
  s.type = type;
  s.unit = std::move(unit);
  s.doc = std::move(doc);
  s.required = required;
  s.default_text = std::move(default_text);
  return s;
}

const SectionSpec& run_section() {
  static const SectionSpec s{
      "run",
      "Time integration (explicit central differences, paper eq. 35) and output.",
      {number("end_time", "s", "simulated end time", 0, true),
       opt(number("time_step_safety", "", "fraction of the critical step actually used", 0, true, 1, false), "0.9"),
       opt(number("time_step", "s", "fixed user step; refused above the stable limit unless force_time_step", 0, false), "0 (automatic)"),
       typed("force_time_step", ValueType::boolean, "", "accept a user time_step above the stable limit", false, "false"),
       typed("step_estimate", ValueType::string, "",
             "the critical step: nodal (the larger of the element estimate and a bound from each node's whole mass, which a badly "
             "shaped tet does not pull down) | element (the element-by-element estimate alone)",
             false, "nodal"),
       typed("output_times", ValueType::number_list, "s", "times at which results are written, exactly (the state at end_time is always written too)",
             false, "[]"),
       opt(number("output_interval", "s", "also write results at every k * interval", 0, false), "0"),
       opt(number("energy_tolerance", "", "energy-balance error, relative to the largest energy, that stops the run as unstable", 0, true), "0.25"),
       typed("gravity", ValueType::vec3, "m/s^2", "body acceleration", false, "[0, 0, 0]"),
       opt(number("gravity_ramp_time", "s", "gravity grows linearly from 0 over this time", 0, false), "0"),
       typed("gravity_curve", ValueType::string, "", "a [curves] name scaling gravity (instead of gravity_ramp_time)", false),
       opt(whole(number("threads", "", "worker threads (0: all cores, at most one per ~4000 tets)", 0, false, 1024, false)), "0"),
       opt(whole(number("history_every", "", "write a history row every N steps (0: about 2000 rows)", 0, false)), "0"),
       opt(whole(number("max_outputs", "", "refuse schedules with more output states than this (a runaway guard)", 1, false, 1e9, false)), "10000"),
       opt(whole(number("max_steps", "", "refuse runs expected to take more steps than this (a runaway guard)", 1, false, 1e15, false)), "1e7"),
       opt(number("minimum_time_step", "s",
                  "mass scaling: tets whose stable step (before the safety factor) falls below this get mass until it is met; the added "
                  "mass is reported per body (0: off)",
                  0, false),
           "0 (off)"),
       opt(number("added_mass_limit", "", "stop the run when mass scaling has added more than this fraction of a body's mass", 0, true, 1, false),
           "0.01"),
       opt(number("checkpoint_interval", "s",
                  "write a restart checkpoint every this much simulated time (and on an interrupt); tactus-solve --restart OUT "
                  "continues a killed run from the newest (0: off)",
                  0, false),
           "0 (off)"),
       opt(number("checkpoint_wall_interval", "s", "also write a checkpoint every this many seconds of wall-clock time (0: off)", 0, false),
           "0 (off)")}};
  return s;
}

const SectionSpec& damping_section() {
  static const SectionSpec s{"damping",
                             "Rayleigh damping A = alpha M + beta K; the beta part is a viscous stress, never an assembled K.",
                             {opt(number("alpha", "1/s", "mass-proportional coefficient", 0, false), "0"),
                              opt(number("beta", "s", "stiffness-proportional coefficient", 0, false), "0")}};
  return s;
}

const SectionSpec& body_section() {
  static const SectionSpec s{
      "bodies",
      "[[bodies]]: one deformable body per entry.",
      {typed("name", ValueType::string, "", "unique body name", true),
       typed("mesh", ValueType::string, "", "gmsh .msh file (relative to the scenario file)", true),
       opt(number("scale", "", "factor applied to mesh coordinates (1e-3 for a mesh in mm)", 0, true), "1"),
       typed("rotate_axis", ValueType::vec3, "", "rotation axis (with rotate_angle; applied after scale, before translate and against)", false),
       opt(number("rotate_angle", "deg", "rotation angle about rotate_axis, right-handed", -360, false, 360, false), "0"),
       typed("rotate_matrix", ValueType::vec3_list, "", "rotation as a matrix, three rows (instead of rotate_axis and rotate_angle)", false),
       typed("rotate_about", ValueType::vec3, "m", "the point the rotation keeps fixed (scaled mesh coordinates)", false, "[0, 0, 0]"),
       typed("translate", ValueType::vec3, "m", "translation applied after scaling", false, "[0, 0, 0]"),
       typed("initial_velocity", ValueType::vec3, "m/s", "uniform initial velocity", false, "[0, 0, 0]"),
       typed("initial_angular_velocity", ValueType::vec3, "rad/s",
             "initial spin about the body's centre of mass: v = initial_velocity + w x (X - centre)", false, "[0, 0, 0]"),
       typed("rigid_velocity", ValueType::vec3, "m/s",
             "prescribed velocity of the centre of each rigid piece of this body (materials of type rigid); with "
             "rigid_angular_velocity, the pieces move as given and their reaction is reported (default: free rigid pieces)",
             false),
       typed("rigid_angular_velocity", ValueType::vec3, "rad/s", "prescribed angular velocity of each rigid piece of this body, about its centre",
             false),
       typed("rigid_curve", ValueType::string, "", "a [curves] name scaling rigid_velocity and rigid_angular_velocity", false),
       typed("against", ValueType::string, "",
             "place this body next to an earlier body: after translate, it is moved along against_axis only, "
             "so that against_gap separates the two bounding boxes along that axis",
             false),
       typed("against_axis", ValueType::string, "", "side of the other body this one lies on: +x, -x, +y, -y, +z or -z", false, "\"+x\""),
       opt(number("against_gap", "m", "gap between the two bodies along against_axis", 0, false), "0"),
       typed("fibres", ValueType::string, "",
             "per-element hgo fibre directions: a .vtu of this mesh's tets with cell data fibre_1, fibre_2 "
             "(overrides the materials' constant fibres)",
             false),
       typed("materials", ValueType::table, "", "physical volume group name -> material name (key \"*\" for every other group)", true)}};
  return s;
}

const SectionSpec& material_common_section() {
  static const SectionSpec s{"materials.<name>",
                             "A named material; `type` selects the law, whose keys follow (see below, one section per law).",
                             {typed("type", ValueType::string, "", material_type_list(), true)}};
  return s;
}

const SectionSpec& boundary_section() {
  static const SectionSpec s{
      "boundary",
      "[[boundary]]: fixed, prescribed-velocity or prescribed-displacement nodes of a body, by physical group or by box; "
      "its reaction force and moment are written in history.csv and run.json.",
      {typed("body", ValueType::string, "", "body name", true),
       typed("group", ValueType::string, "", "physical surface or volume group whose nodes are constrained", false),
       typed("box", ValueType::vec3_list, "m", "[[xmin,ymin,zmin],[xmax,ymax,zmax]]: nodes inside (placed coordinates)", false),
       typed("type", ValueType::string, "", "fixed | velocity | displacement", true),
       typed("velocity", ValueType::vec3, "m/s", "prescribed velocity (type = velocity), times curve(t)", false, "[0, 0, 0]"),
       typed("displacement", ValueType::vec3, "m", "prescribed displacement (type = displacement), times curve(t), exact at every step", false,
             "[0, 0, 0]"),
       typed("curve", ValueType::string, "", "a [curves] name scaling velocity or displacement (default: constant 1)", false),
       typed("components", ValueType::string, "", "constrained components, any of \"xyz\"", false, "\"xyz\""),
       typed("name", ValueType::string, "", "name of the reaction columns reaction_<name>_x.. (letters, digits, _)", false, "boundary<k>"),
       typed("moment_about", ValueType::vec3, "m", "point the reaction moment is taken about", false, "[0, 0, 0]")}};
  return s;
}

const SectionSpec& load_section() {
  static const SectionSpec s{
      "load",
      "[[load]]: a follower pressure on a physical surface group of a body: normal to the current surface, on the current "
      "area, positive pushing into the body.",
      {typed("body", ValueType::string, "", "body name", true), typed("group", ValueType::string, "", "physical surface group", true),
       typed("type", ValueType::string, "", "pressure", true), number("pressure", "Pa", "pressure (times curve(t))"),
       typed("curve", ValueType::string, "", "a [curves] name scaling the pressure (default: constant 1)", false)}};
  return s;
}

const SectionSpec& curve_section() {
  static const SectionSpec s{
      "curves.<name>",
      "A named dimensionless factor of time for boundaries, loads and gravity: piecewise linear through (times, values), "
      "constant beyond the ends, or a smooth step from 0 to 1.",
      {typed("times", ValueType::number_list, "s", "increasing times of the table", false),
       typed("values", ValueType::number_list, "", "the factor at each of times", false),
       typed("smooth_step", ValueType::number_list, "s", "[t0, t1]: 0 before t0, 1 after t1, 3s^2 - 2s^3 between (instead of a table)", false)}};
  return s;
}

const SectionSpec& contact_section() {
  static const SectionSpec s{
      "contact",
      "[[contact]]: bi-potential Coulomb contact (paper §2.1), slave nodes of one body's surface against "
      "another body's surface (master) or a rigid plane. The finer surface makes the better slave; against a rigid body (material type rigid) the "
      "deformable surface is the slave. A master equal to the slave "
      "(same body and surface) is self-contact: skin on skin, each node against the faces of the same surface that face it, "
      "its own neighbourhood excluded (node_to_surface, one pass).",
      {typed("slave_body", ValueType::string, "", "body whose surface nodes are the slaves", true),
       typed("slave_surface", ValueType::string, "", "physical surface group of slave_body (e.g. skin)", true),
       typed("master_body", ValueType::string, "", "body owning the master surface (omit with plane)", false),
       typed("master_surface", ValueType::string, "", "physical surface group of master_body", false),
       typed("plane", ValueType::vec3_list, "m", "rigid plane master: [[point], [outward normal]] (instead of master_body)", false),
       opt(number("friction", "", "Coulomb friction coefficient mu", 0, false), "0"),
       typed("two_pass", ValueType::boolean, "", "also the master's nodes against the slave surface", false, "false"),
       typed("edge_pass", ValueType::boolean, "",
             "mortar: also the master's convex edge and corner nodes (faces meeting at more than 30 deg; not those of rigid pieces) "
             "against the slave surface, node to surface, so a sharp master edge cannot cut into the slave surface between its nodes",
             false, "true"),
       typed("method", ValueType::string, "",
             "node_to_surface (each slave node on its closest master point) | mortar (segment-to-segment: each slave node's "
             "tributary surface integrated over the master triangles it overlaps, dual multipliers)",
             false, "mortar; node_to_surface for self-contact, a rigid plane or two_pass")}};
  return s;
}

const SectionSpec& contact_solver_section() {
  static const SectionSpec s{
      "contact_solver",
      "Uzawa iterations of the bi-potential contact solver (Gauss-Seidel over the contact nodes).",
      {opt(number("tolerance", "", "stop when max |dr| <= tolerance * max |r| over the contact nodes", 0, true, 1, true), "1e-6"),
       opt(whole(number("max_iterations", "", "iteration limit per step (reached: a warning, the run goes on)", 1, false, 1e6, false)), "200"),
       opt(number("search_factor", "", "search distance and penetration band, in mean master edge lengths", 0, true, 10, false), "0.5"),
       opt(number("verlet_skin", "",
                  "node-to-surface search: candidate triangles are gathered within the band plus this skin (in mean master edge lengths) "
                  "and kept until a node has moved half the skin (0: search every step)",
                  0, false, 10, false),
           "0.5"),
       opt(number("pressure_window", "s",
                  "the reported contact pressure is r_n / A averaged over an exponential window of max(this, 10 initial critical steps), "
                  "so an impact's peak does not grow like 1/dt",
                  0, true),
           "1e-5"),
       opt(number("pressure_average_area", "m^2",
                  "at each output the contact pressure field is also averaged over discs of this area on the slave surfaces, and the largest "
                  "average is reported (run.json contact.at_outputs), a peak that converges with the mesh",
                  0, true),
           "25e-6"),
       opt(number("recovery_speed", "m/s",
                  "a node found inside its master deeper than this speed times the step (a penetration the previous step did not make, "
                  "e.g. a node sliding back over a master's edge) is pushed out at this speed rather than in one step, which would give it "
                  "depth / dt (run.json contact.uzawa.recovering_rows counts them)",
                  0, true),
           "1.0"),
       opt(whole(number("sweep_blocks", "",
                        "the Uzawa sweep is cut into at most this many slabs along the contact (at most one per 256 rows), the even ones swept "
                        "in parallel, then the odd ones, then the rows they share in order; the same bits on any thread count; 1: one "
                        "Gauss-Seidel sweep in row order",
                        1, false, 4096, false)),
           "16")}};
  return s;
}

const SectionSpec& pipeline_section() {
  static const SectionSpec s{
      "pipeline.meshes",
      "[[pipeline.meshes]]: how tactus-pipeline makes each mesh this scenario uses (tactus-solve only checks these "
      "entries; the pipeline runs tactus-mesh for them).",
      {typed("output", ValueType::string, "",
             "the mesh file (or, kind = fibres, the fibre file) a [[bodies]] entry names, relative to the pipeline's work folder", true),
       typed("kind", ValueType::string, "",
             "labels (from the segmented CT) | box | stl | fibres (rule-based hgo fibre directions of the mesh `file`: tactus-mesh fibres)", true),
       typed("args", ValueType::string, "", "tactus-mesh options (e.g. \"--size 0.04 0.08 0.16 --element-size 0.008\")", false, "\"\""),
       typed("file", ValueType::string, "",
             "kind = stl: the closed STL surface, relative to the scenario's folder; kind = fibres: the mesh, relative to the work folder", false)}};
  return s;
}

const char* type_name(ValueType t) {
  switch (t) {
    case ValueType::number:
      return "a number";
    case ValueType::integer:
      return "an integer";
    case ValueType::boolean:
      return "true or false";
    case ValueType::string:
      return "a string";
    case ValueType::vec3:
      return "an array of 3 numbers";
    case ValueType::number_list:
      return "an array of numbers";
    case ValueType::vec3_list:
      return "an array of [x, y, z] arrays";
    case ValueType::table:
      return "a table";
    case ValueType::table_list:
      return "an array of tables";
  }
  return "";
}

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& expected, const std::string& found = {}) const {
    throw InputError(file_, key, expected, found);
  }

  // Unknown keys and missing required keys of one table.
  void check_keys(const toml::table& t, const SectionSpec& spec, const std::string& path, const std::set<std::string>& extra = {}) const {
    for (const auto& [k, node] : t) {
      const std::string key(k.str());
      if (!spec.find(key) && !extra.count(key)) {
        std::string allowed;
        for (const auto& s : spec.keys) allowed += (allowed.empty() ? "" : ", ") + s.key;
        for (const auto& s : extra) allowed += ", " + s;
        fail(join(path, key), "one of the keys " + allowed, "unknown key \"" + key + "\"");
      }
    }
    for (const auto& s : spec.keys)
      if (s.required && !t.contains(s.key)) fail(join(path, s.key), s.doc + " (" + type_name(s.type) + ")", "missing");
  }

  double number(const toml::table& t, const ValueSpec& s, const std::string& path, double def) const {
    const toml::node* n = t.get(s.key);
    if (!n) return def;
    auto v = n->value<double>();
    if (!v || n->is_boolean()) fail(join(path, s.key), std::string(type_name(ValueType::number)) + unit_suffix(s), describe(*n));
    check_range(*v, s, join(path, s.key));
    return *v;
  }

  // A whole number: a TOML integer, or a float without a fractional part (1e7 as max_steps documents
  // it); 2.5 is refused naming the key, never rounded.
  std::int64_t integer(const toml::table& t, const ValueSpec& s, const std::string& path) const {
    const toml::node* n = t.get(s.key);
    std::optional<double> v;
    if (n && n->is_integer()) v = static_cast<double>(*n->value<std::int64_t>());
    if (n && n->is_floating_point()) v = *n->value<double>();
    if (!v || !std::isfinite(*v) || *v != std::floor(*v) || std::abs(*v) > 9.0e18)
      fail(join(path, s.key), "an integer (a whole number)" + unit_suffix(s), n ? describe(*n) : "missing");
    check_range(*v, s, join(path, s.key));
    return static_cast<std::int64_t>(*v);
  }
  std::int64_t integer(const toml::table& t, const ValueSpec& s, const std::string& path, std::int64_t def) const {
    return t.contains(s.key) ? integer(t, s, path) : def;
  }

  void check_range(double v, const ValueSpec& s, const std::string& key) const {
    if (!s.in_range(v)) {
      std::ostringstream f;
      f << v;
      fail(key, "a value " + s.range_text() + unit_suffix(s), f.str());
    }
  }

  bool boolean(const toml::table& t, const ValueSpec& s, const std::string& path, bool def) const {
    const toml::node* n = t.get(s.key);
    if (!n) return def;
    if (!n->is_boolean()) fail(join(path, s.key), "true or false", describe(*n));
    return *n->value<bool>();
  }

  std::string string(const toml::table& t, const ValueSpec& s, const std::string& path, std::string def = {}) const {
    const toml::node* n = t.get(s.key);
    if (!n) return def;
    if (!n->is_string()) fail(join(path, s.key), "a string", describe(*n));
    return *n->value<std::string>();
  }

  Vec3 vec3(const toml::node& n, const std::string& key, const std::string& unit) const {
    const toml::array* a = n.as_array();
    Vec3 v{};
    if (!a || a->size() != 3) fail(key, "an array of 3 numbers" + (unit.empty() ? "" : " in " + unit), describe(n));
    for (std::size_t i = 0; i < 3; ++i) {
      auto x = (*a)[i].value<double>();
      if (!x || (*a)[i].is_boolean() || !std::isfinite(*x)) fail(key, "an array of 3 finite numbers", describe(n));
      v[i] = *x;
    }
    return v;
  }

  Vec3 vec3(const toml::table& t, const ValueSpec& s, const std::string& path, Vec3 def) const {
    const toml::node* n = t.get(s.key);
    return n ? vec3(*n, join(path, s.key), s.unit) : def;
  }

  std::vector<Vec3> vec3_list(const toml::table& t, const ValueSpec& s, const std::string& path) const {
    std::vector<Vec3> out;
    const toml::node* n = t.get(s.key);
    if (!n) return out;
    const toml::array* a = n->as_array();
    if (!a) fail(join(path, s.key), "an array of [x, y, z] arrays", describe(*n));
    for (std::size_t i = 0; i < a->size(); ++i) out.push_back(vec3((*a)[i], join(path, s.key) + "[" + std::to_string(i) + "]", s.unit));
    return out;
  }

  std::vector<double> number_list(const toml::table& t, const ValueSpec& s, const std::string& path) const {
    std::vector<double> out;
    const toml::node* n = t.get(s.key);
    if (!n) return out;
    const toml::array* a = n->as_array();
    if (!a) fail(join(path, s.key), "an array of numbers", describe(*n));
    for (std::size_t i = 0; i < a->size(); ++i) {
      auto x = (*a)[i].value<double>();
      if (!x || (*a)[i].is_boolean() || !std::isfinite(*x) || (s.unit == "s" && *x < 0))
        fail(join(path, s.key) + "[" + std::to_string(i) + "]", s.unit == "s" ? "a time >= 0 in s" : "a finite number", describe((*a)[i]));
      out.push_back(*x);
    }
    return out;
  }

  const toml::table& table(const toml::node& n, const std::string& key) const {
    const toml::table* t = n.as_table();
    if (!t) fail(key, "a table", describe(n));
    return *t;
  }

  // Each table of an array of tables ([[key]]), its keys checked against spec, handed to
  // visit(table, path) with path "key[i]" for the messages.
  template <class Visit>
  void each_table(const toml::node& n, const std::string& key, const SectionSpec& spec, Visit&& visit) const {
    const toml::array* arr = n.as_array();
    if (!arr) fail(key, "[[" + key + "]] tables", describe(n));
    for (std::size_t i = 0; i < arr->size(); ++i) {
      const std::string path = key + "[" + std::to_string(i) + "]";
      const toml::table& t = table((*arr)[i], path);
      check_keys(t, spec, path);
      visit(t, path);
    }
  }

  static std::string join(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }
  static std::string unit_suffix(const ValueSpec& s) { return s.unit.empty() ? "" : " in " + s.unit; }
  static std::string describe(const toml::node& n) {
    std::ostringstream o;
    if (n.is_table()) return "a table";
    if (n.is_array()) {  // its values, so the wrong one shows: "[0.1, nan, 0]"
      const toml::array& a = *n.as_array();
      o << '[';
      for (std::size_t i = 0; i < a.size() && i < 6; ++i) o << (i ? ", " : "") << describe(a[i]);
      o << (a.size() > 6 ? ", ... (" + std::to_string(a.size()) + " values)]" : "]");
      return o.str();
    }
    if (n.is_string()) {
      o << '"' << *n.value<std::string>() << '"';  // (not "\"" + s: GCC 12 -Wrestrict false positive)
      return o.str();
    }
    if (n.is_boolean()) return *n.value<bool>() ? "true" : "false";
    if (auto d = n.value<double>()) {
      o << *d;
      return o.str();
    }
    return "a value of another type";
  }

 private:
  std::string file_;
};

}  // namespace

std::vector<SectionSpec> scenario_reference() {
  std::vector<SectionSpec> out{run_section(),      damping_section(), body_section(),    material_common_section(), curve_section(),
                               boundary_section(), load_section(),    contact_section(), contact_solver_section(),  pipeline_section()};
  for (const MaterialType* m : material_types()) out.push_back(m->parameters);
  return out;
}

std::string scenario_reference_markdown() {
  std::ostringstream o;
  o << "# scenario.toml reference\n\n"
    << "Generated by `tactus-solve keys` from the declarations the scenario reader validates with "
       "(solver/src/scenario.cpp, solver/src/materials/*.cpp). SI units throughout.\n"
       "Unknown keys, missing required keys and values outside their range are errors naming the key.\n";
  for (const auto& s : scenario_reference()) {
    o << "\n## " << s.name << "\n\n" << s.doc << "\n\n| key | type | unit | valid | default | meaning |\n|---|---|---|---|---|---|\n";
    for (const auto& k : s.keys) {
      o << "| `" << k.key << "` | " << type_name(k.type) << " | " << (k.unit.empty() ? "-" : k.unit) << " | "
        << (k.range_text().empty() ? "-" : k.range_text()) << " | " << (k.required ? "**required**" : (k.default_text.empty() ? "-" : k.default_text))
        << " | " << k.doc << " |\n";
    }
  }
  return o.str();
}

namespace {

// The sections of scenario.toml, one reader each (called in this order by read_scenario).
void read_run(const Reader& r, const toml::table& root, Scenario& sc) {
  {  // [run]
    const auto& spec = run_section();
    const toml::table& t = r.table(*root.get("run"), "run");
    r.check_keys(t, spec, "run");
    RunSpec& run = sc.run;
    run.end_time = r.number(t, *spec.find("end_time"), "run", 0);
    run.time_step_safety = r.number(t, *spec.find("time_step_safety"), "run", 0.9);
    run.time_step = r.number(t, *spec.find("time_step"), "run", 0);
    run.force_time_step = r.boolean(t, *spec.find("force_time_step"), "run", false);
    if (const std::string estimate = r.string(t, *spec.find("step_estimate"), "run"); !estimate.empty()) {
      if (estimate != "nodal" && estimate != "element") r.fail("run.step_estimate", "\"nodal\" or \"element\"", "\"" + estimate + "\"");
      run.nodal_step_bound = estimate == "nodal";
    }
    run.output_times = r.number_list(t, *spec.find("output_times"), "run");
    run.output_interval = r.number(t, *spec.find("output_interval"), "run", 0);
    run.energy_tolerance = r.number(t, *spec.find("energy_tolerance"), "run", 0.25);
    run.gravity = r.vec3(t, *spec.find("gravity"), "run", {0, 0, 0});
    run.gravity_ramp_time = r.number(t, *spec.find("gravity_ramp_time"), "run", 0);
    run.gravity_curve = r.string(t, *spec.find("gravity_curve"), "run");
    if (!run.gravity_curve.empty() && run.gravity_ramp_time > 0) r.fail("run", "either gravity_ramp_time or gravity_curve", "both");
    run.threads = static_cast<int>(r.integer(t, *spec.find("threads"), "run", 0));
    run.history_every = static_cast<int>(r.integer(t, *spec.find("history_every"), "run", 0));
    run.max_outputs = static_cast<double>(r.integer(t, *spec.find("max_outputs"), "run", 10000));
    run.max_steps = static_cast<double>(r.integer(t, *spec.find("max_steps"), "run", 10000000));
    run.minimum_time_step = r.number(t, *spec.find("minimum_time_step"), "run", 0);
    run.added_mass_limit = r.number(t, *spec.find("added_mass_limit"), "run", 0.01);
    run.checkpoint_interval = r.number(t, *spec.find("checkpoint_interval"), "run", 0);
    run.checkpoint_wall_interval = r.number(t, *spec.find("checkpoint_wall_interval"), "run", 0);
    // Checkpoints count against the same runaway guard as output states (1e-300 s would never end).
    if (run.checkpoint_interval > 0 && run.end_time / run.checkpoint_interval > run.max_outputs) {
      std::ostringstream e, f;
      e << "an interval >= run.end_time / run.max_outputs = " << run.end_time / run.max_outputs
        << " s (at most run.max_outputs = " << static_cast<long long>(run.max_outputs) << " checkpoints)";
      f << run.checkpoint_interval << " s (" << run.end_time / run.checkpoint_interval << " checkpoints)";
      r.fail("run.checkpoint_interval", e.str(), f.str());
    }
    for (double time : run.output_times)
      if (time > run.end_time) r.fail("run.output_times", "times <= run.end_time", std::to_string(time));
    // Counted before anything is built: an interval of 1e-9 s over 1000 s is 10^12 states.
    if (run.output_interval > 0) {
      const double count = std::floor(run.end_time / run.output_interval * (1 + 1e-12));
      if (count + static_cast<double>(run.output_times.size()) > run.max_outputs) {
        std::ostringstream f;
        f << count << " states (every " << run.output_interval << " s to " << run.end_time << " s)";
        r.fail("run.output_interval",
               "at most run.max_outputs = " + std::to_string(static_cast<long long>(run.max_outputs)) +
                   " output states (raise run.max_outputs to allow more)",
               f.str());
      }
    }
    if (static_cast<double>(run.output_times.size()) > run.max_outputs)
      r.fail("run.output_times", "at most run.max_outputs output states", std::to_string(run.output_times.size()));
  }
}

void read_damping(const Reader& r, const toml::table& root, Scenario& sc) {
  if (const toml::node* n = root.get("damping")) {
    const auto& spec = damping_section();
    const toml::table& t = r.table(*n, "damping");
    r.check_keys(t, spec, "damping");
    sc.damping.alpha = r.number(t, *spec.find("alpha"), "damping", 0);
    sc.damping.beta = r.number(t, *spec.find("beta"), "damping", 0);
  }
}

void read_materials(const Reader& r, const toml::table& root, Scenario& sc, const std::string& fname) {
  {  // [materials.<name>]: validated against the law's own declarations (material.hpp)
    const toml::table& mats = r.table(*root.get("materials"), "materials");
    if (mats.empty()) r.fail("materials", "at least one [materials.<name>] table", "none");
    for (const auto& [k, node] : mats) {
      const std::string name(k.str()), path = "materials." + name;
      const toml::table& t = r.table(node, path);
      MaterialInstance m;
      m.name = name;
      if (!t.contains("type")) r.fail(path + ".type", "one of " + material_type_list(), "missing");
      m.type = r.string(t, *material_common_section().find("type"), path);
      const MaterialType* type = nullptr;
      for (const MaterialType* ty : material_types())
        if (ty->name == m.type) type = ty;
      if (!type) r.fail(path + ".type", "one of " + material_type_list(), "\"" + m.type + "\"");
      r.check_keys(t, type->parameters, path, {"type"});
      for (const ValueSpec& ps : type->parameters.keys) {
        if (ps.type == ValueType::number)
          m.values.numbers[ps.key] = r.number(t, ps, path, 0);
        else if (ps.type == ValueType::vec3_list && t.contains(ps.key))
          m.values.vectors[ps.key] = r.vec3_list(t, ps, path);
        else if (ps.type == ValueType::string && t.contains(ps.key))
          m.values.strings[ps.key] = r.string(t, ps, path);
        else if (ps.type == ValueType::integer && t.contains(ps.key))
          m.values.numbers[ps.key] = static_cast<double>(r.integer(t, ps, path));
      }
      m.values.source = fname;
      Material::make(m.type, m.values, path);  // the law's own checks (hgo: two non-zero fibre directions)
      sc.materials[name] = m;
    }
  }
}

// rotate_axis + rotate_angle (Rodrigues' formula) or rotate_matrix (checked orthonormal, det +1).
void read_rotation(const Reader& r, const toml::table& t, const SectionSpec& spec, const std::string& path, BodySpec& b) {
  const bool by_axis = t.contains("rotate_axis") || t.contains("rotate_angle"), by_matrix = t.contains("rotate_matrix");
  if (by_axis && by_matrix) r.fail(path + ".rotate_matrix", "either rotate_matrix or rotate_axis + rotate_angle", "both");
  b.rotate_about = r.vec3(t, *spec.find("rotate_about"), path, {0, 0, 0});
  if (by_axis) {
    if (!t.contains("rotate_axis") || !t.contains("rotate_angle"))
      r.fail(path + ".rotate_axis", "rotate_axis and rotate_angle together", "one of them");
    const Vec3 a = r.vec3(t, *spec.find("rotate_axis"), path, {0, 0, 1});
    const double n = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (!(n > 0)) r.fail(path + ".rotate_axis", "a non-zero axis", "[0, 0, 0]");
    const double th = r.number(t, *spec.find("rotate_angle"), path, 0) * M_PI / 180.0;
    const double x = a[0] / n, y = a[1] / n, z = a[2] / n, c = std::cos(th), s = std::sin(th), C = 1 - c;
    b.rotation = {Vec3{c + x * x * C, x * y * C - z * s, x * z * C + y * s}, Vec3{y * x * C + z * s, c + y * y * C, y * z * C - x * s},
                  Vec3{z * x * C - y * s, z * y * C + x * s, c + z * z * C}};
    b.rotated = true;
  } else if (by_matrix) {
    const auto rows = r.vec3_list(t, *spec.find("rotate_matrix"), path);
    if (rows.size() != 3)
      r.fail(path + ".rotate_matrix", "three rows [[r11, r12, r13], [r21, r22, r23], [r31, r32, r33]]", std::to_string(rows.size()) + " rows");
    double worst = 0;  // |R R^T - I|
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        worst = std::max(worst, std::abs(rows[i][0] * rows[j][0] + rows[i][1] * rows[j][1] + rows[i][2] * rows[j][2] - (i == j ? 1.0 : 0.0)));
    const double det = rows[0][0] * (rows[1][1] * rows[2][2] - rows[1][2] * rows[2][1]) -
                       rows[0][1] * (rows[1][0] * rows[2][2] - rows[1][2] * rows[2][0]) +
                       rows[0][2] * (rows[1][0] * rows[2][1] - rows[1][1] * rows[2][0]);
    if (worst > 1e-9 || det < 0) {
      std::ostringstream f;
      f << "|R R^T - I| = " << worst << ", det " << det;
      r.fail(path + ".rotate_matrix", "a rotation: orthonormal rows (to 1e-9) and determinant +1", f.str());
    }
    b.rotation = {rows[0], rows[1], rows[2]};
    b.rotated = true;
  }
}

void read_bodies(const Reader& r, const toml::table& root, Scenario& sc, const fs::path& base) {
  {  // [[bodies]]
    const auto& spec = body_section();
    const toml::array* arr = root.get("bodies")->as_array();
    if (arr && arr->empty()) r.fail("bodies", "one or more [[bodies]] tables", "none");
    std::set<std::string> names;
    r.each_table(*root.get("bodies"), "bodies", spec, [&](const toml::table& t, const std::string& path) {
      BodySpec b;
      b.name = r.string(t, *spec.find("name"), path);
      if (!names.insert(b.name).second) r.fail(path + ".name", "a unique body name", "\"" + b.name + "\" twice");
      b.mesh = base / r.string(t, *spec.find("mesh"), path);
      b.scale = r.number(t, *spec.find("scale"), path, 1.0);
      read_rotation(r, t, spec, path, b);
      b.translate = r.vec3(t, *spec.find("translate"), path, {0, 0, 0});
      b.initial_velocity = r.vec3(t, *spec.find("initial_velocity"), path, {0, 0, 0});
      b.initial_angular_velocity = r.vec3(t, *spec.find("initial_angular_velocity"), path, {0, 0, 0});
      if (t.contains("rigid_velocity") || t.contains("rigid_angular_velocity")) {
        b.rigid_velocity = r.vec3(t, *spec.find("rigid_velocity"), path, {0, 0, 0});
        b.rigid_angular_velocity = r.vec3(t, *spec.find("rigid_angular_velocity"), path, {0, 0, 0});
      } else if (t.contains("rigid_curve")) {
        r.fail(path + ".rigid_curve", "rigid_velocity or rigid_angular_velocity with it", "a curve alone");
      }
      b.rigid_curve = r.string(t, *spec.find("rigid_curve"), path);
      if (t.contains("fibres")) b.fibres = base / r.string(t, *spec.find("fibres"), path);
      if (t.contains("against")) {
        b.against = r.string(t, *spec.find("against"), path);
        if (!names.count(b.against) || b.against == b.name)
          r.fail(path + ".against", "the name of a [[bodies]] entry listed before this one", "\"" + b.against + "\"");
        const std::string axis = r.string(t, *spec.find("against_axis"), path, "+x");
        if (axis.size() != 2 || (axis[0] != '+' && axis[0] != '-') || axis[1] < 'x' || axis[1] > 'z')
          r.fail(path + ".against_axis", "one of +x, -x, +y, -y, +z, -z", "\"" + axis + "\"");
        b.against_axis = axis[1] - 'x';
        b.against_side = axis[0] == '+' ? 1 : -1;
        b.against_gap = r.number(t, *spec.find("against_gap"), path, 0);
      } else if (t.contains("against_axis") || t.contains("against_gap")) {
        r.fail(path + ".against", "the body to place against (against_axis and against_gap need it)", "missing");
      }
      const toml::table& mt = r.table(*t.get("materials"), path + ".materials");
      for (const auto& [gk, gv] : mt) {
        const std::string group(gk.str());
        if (!gv.is_string()) r.fail(path + ".materials." + group, "a material name (string)", Reader::describe(gv));
        const std::string mat = *gv.value<std::string>();
        if (!sc.materials.count(mat)) {
          std::string known;
          for (const auto& [n, m] : sc.materials) known += (known.empty() ? "" : ", ") + n;
          r.fail(path + ".materials." + group, "a material defined under [materials] (" + known + ")", "\"" + mat + "\"");
        }
        b.materials[group] = mat;
      }
      sc.bodies.push_back(b);
    });
  }
}

// A [[bodies]] name, or an InputError naming the key.
void require_body(const Reader& r, const Scenario& sc, const std::string& name, const std::string& key) {
  for (const auto& b : sc.bodies)
    if (b.name == name) return;
  r.fail(key, "the name of a [[bodies]] entry", "\"" + name + "\"");
}

// A [curves] name (empty: none), or an InputError listing the curves.
void require_curve(const Reader& r, const Scenario& sc, const std::string& name, const std::string& key) {
  if (name.empty() || sc.curves.count(name)) return;
  std::string known;
  for (const auto& [n, c] : sc.curves) known += (known.empty() ? "" : ", ") + n;
  r.fail(key, "the name of a [curves.<name>] table" + (known.empty() ? std::string(" (there is none)") : " (" + known + ")"), "\"" + name + "\"");
}

// A boundary name for the history columns: letters, digits and _, unique.
void require_column_name(const Reader& r, const Scenario& sc, const std::string& name, const std::string& key) {
  bool ok = !name.empty();
  for (char c : name) ok = ok && (std::isalnum(static_cast<unsigned char>(c)) || c == '_');
  if (!ok) r.fail(key, "letters, digits and _ only (it names history columns)", "\"" + name + "\"");
  for (const auto& b : sc.boundaries)
    if (b.name == name) r.fail(key, "a name no other [[boundary]] has", "\"" + name + "\" twice");
}

void read_curves(const Reader& r, const toml::table& root, Scenario& sc) {
  if (const toml::node* n = root.get("curves")) {  // [curves.<name>]
    const auto& spec = curve_section();
    for (const auto& [k, node] : r.table(*n, "curves")) {
      const std::string name(k.str()), path = "curves." + name;
      const toml::table& t = r.table(node, path);
      r.check_keys(t, spec, path);
      CurveSpec c;
      c.name = name;
      if (t.contains("smooth_step")) {
        if (t.contains("times") || t.contains("values")) r.fail(path, "either times + values or smooth_step", "both");
        const auto ts = r.number_list(t, *spec.find("smooth_step"), path);
        if (ts.size() != 2 || !(ts[1] > ts[0]))
          r.fail(path + ".smooth_step", "[t0, t1] with t1 > t0 >= 0", "an array of " + std::to_string(ts.size()));
        c.smooth_step = true, c.t0 = ts[0], c.t1 = ts[1];
      } else {
        c.times = r.number_list(t, *spec.find("times"), path);
        c.values = r.number_list(t, *spec.find("values"), path);
        if (c.times.empty() || c.times.size() != c.values.size())
          r.fail(path, "times and values of the same length (or smooth_step)",
                 std::to_string(c.times.size()) + " times, " + std::to_string(c.values.size()) + " values");
        for (std::size_t i = 1; i < c.times.size(); ++i)
          if (!(c.times[i] > c.times[i - 1])) r.fail(path + ".times", "strictly increasing times", "not increasing at index " + std::to_string(i));
      }
      sc.curves[name] = c;
    }
  }
  require_curve(r, sc, sc.run.gravity_curve, "run.gravity_curve");
}

void read_loads(const Reader& r, const toml::table& root, Scenario& sc) {
  if (const toml::node* n = root.get("load")) {  // [[load]]
    const auto& spec = load_section();
    r.each_table(*n, "load", spec, [&](const toml::table& t, const std::string& path) {
      LoadSpec l;
      l.body = r.string(t, *spec.find("body"), path);
      require_body(r, sc, l.body, path + ".body");
      l.group = r.string(t, *spec.find("group"), path);
      if (const std::string type = r.string(t, *spec.find("type"), path); type != "pressure")
        r.fail(path + ".type", "\"pressure\"", "\"" + type + "\"");
      l.pressure = r.number(t, *spec.find("pressure"), path, 0);
      if (!std::isfinite(l.pressure)) r.fail(path + ".pressure", "a finite pressure in Pa", "not finite");
      l.curve = r.string(t, *spec.find("curve"), path);
      require_curve(r, sc, l.curve, path + ".curve");
      sc.loads.push_back(l);
    });
  }
}

void read_boundaries(const Reader& r, const toml::table& root, Scenario& sc) {
  if (const toml::node* n = root.get("boundary")) {  // [[boundary]]
    const auto& spec = boundary_section();
    r.each_table(*n, "boundary", spec, [&](const toml::table& t, const std::string& path) {
      BoundarySpec bc;
      bc.body = r.string(t, *spec.find("body"), path);
      require_body(r, sc, bc.body, path + ".body");
      bc.group = r.string(t, *spec.find("group"), path);
      const auto box = r.vec3_list(t, *spec.find("box"), path);
      if (t.contains("box")) {
        if (box.size() != 2) r.fail(path + ".box", "[[xmin, ymin, zmin], [xmax, ymax, zmax]]");
        bc.box = std::array<Vec3, 2>{box[0], box[1]};
      }
      if (bc.group.empty() == !bc.box.has_value()) r.fail(path, "exactly one of `group` or `box`");
      bc.type = r.string(t, *spec.find("type"), path);
      if (bc.type != "fixed" && bc.type != "velocity" && bc.type != "displacement")
        r.fail(path + ".type", "\"fixed\", \"velocity\" or \"displacement\"", "\"" + bc.type + "\"");
      bc.velocity = r.vec3(t, *spec.find("velocity"), path, {0, 0, 0});
      bc.displacement = r.vec3(t, *spec.find("displacement"), path, {0, 0, 0});
      if (t.contains("velocity") && bc.type != "velocity")
        r.fail(path + ".velocity", "type = \"velocity\" with a velocity", "type \"" + bc.type + "\"");
      if (t.contains("displacement") && bc.type != "displacement")
        r.fail(path + ".displacement", "type = \"displacement\" with a displacement", "type \"" + bc.type + "\"");
      bc.curve = r.string(t, *spec.find("curve"), path);
      if (!bc.curve.empty() && bc.type == "fixed") r.fail(path + ".curve", "a curve only for type velocity or displacement", "type \"fixed\"");
      require_curve(r, sc, bc.curve, path + ".curve");
      bc.name = r.string(t, *spec.find("name"), path, "boundary" + std::to_string(sc.boundaries.size()));
      require_column_name(r, sc, bc.name, path + ".name");
      bc.moment_about = r.vec3(t, *spec.find("moment_about"), path, {0, 0, 0});
      const std::string comps = r.string(t, *spec.find("components"), path, "xyz");
      bc.components = {false, false, false};
      if (comps.empty()) r.fail(path + ".components", "one or more of x, y, z", "\"\"");
      for (char c : comps) {
        if (c < 'x' || c > 'z') r.fail(path + ".components", "letters among x, y, z", "\"" + comps + "\"");
        bc.components[c - 'x'] = true;
      }
      sc.boundaries.push_back(bc);
    });
  }
}

void read_contacts(const Reader& r, const toml::table& root, Scenario& sc) {
  if (const toml::node* n = root.get("contact")) {  // [[contact]]
    const auto& spec = contact_section();
    r.each_table(*n, "contact", spec, [&](const toml::table& t, const std::string& path) {
      ContactSpec c;
      c.slave_body = r.string(t, *spec.find("slave_body"), path);
      require_body(r, sc, c.slave_body, path + ".slave_body");
      c.slave_surface = r.string(t, *spec.find("slave_surface"), path);
      c.master_body = r.string(t, *spec.find("master_body"), path);
      c.master_surface = r.string(t, *spec.find("master_surface"), path);
      const auto plane = r.vec3_list(t, *spec.find("plane"), path);
      if (t.contains("plane")) {
        if (plane.size() != 2) r.fail(path + ".plane", "[[x, y, z], [nx, ny, nz]]: a point and the outward normal");
        if (!(std::sqrt(plane[1][0] * plane[1][0] + plane[1][1] * plane[1][1] + plane[1][2] * plane[1][2]) > 0))
          r.fail(path + ".plane", "a non-zero normal", "zero vector");
        c.plane = std::array<Vec3, 2>{plane[0], plane[1]};
        if (t.contains("master_body") || t.contains("master_surface")) r.fail(path, "either `plane` or `master_body` + `master_surface`", "both");
      } else {
        if (c.master_body.empty() || c.master_surface.empty()) r.fail(path, "`master_body` and `master_surface` (or a rigid `plane`)", "missing");
        require_body(r, sc, c.master_body, path + ".master_body");
      }
      c.friction = r.number(t, *spec.find("friction"), path, 0);
      c.two_pass = r.boolean(t, *spec.find("two_pass"), path, false);
      c.edge_pass = r.boolean(t, *spec.find("edge_pass"), path, true);
      c.method = r.string(t, *spec.find("method"), path, "");
      if (is_self_contact(c)) {
        const std::string what = "\"" + c.slave_body + "/" + c.slave_surface + "\" against itself (self-contact)";
        if (c.method == "mortar") r.fail(path + ".method", "node_to_surface for self-contact", what + " with mortar");
        if (c.two_pass) r.fail(path + ".two_pass", "false for self-contact (every node of the surface is already a slave)", what + " with two_pass");
      }
      if (!c.method.empty() && c.method != "node_to_surface" && c.method != "mortar")
        r.fail(path + ".method", "\"node_to_surface\" or \"mortar\"", "\"" + c.method + "\"");
      if (c.method == "mortar" && c.plane)
        r.fail(path + ".method", "node_to_surface for a rigid plane (it has no surface to integrate over)", "mortar");
      if (c.two_pass && c.plane) r.fail(path + ".two_pass", "false for a rigid plane", "true");
      if (c.two_pass && c.method == "mortar") r.fail(path + ".two_pass", "false with mortar (its rows already weigh the master's nodes)", "true");
      if (t.contains("edge_pass") && c.edge_pass && contact_method(c) != "mortar")
        r.fail(path + ".edge_pass",
               "true only with mortar (node to surface has two_pass; self-contact and a rigid plane have no master edges to add)",
               "true with " + contact_method(c));
      sc.contacts.push_back(c);
    });
  }
}

void read_pipeline(const Reader& r, const toml::table& root) {
  if (const toml::node* n = root.get("pipeline")) {  // checked here, used by tactus-pipeline
    const toml::table& t = r.table(*n, "pipeline");
    r.check_keys(t, SectionSpec{"pipeline", "", {typed("meshes", ValueType::table_list, "", "[[pipeline.meshes]] entries", false)}}, "pipeline");
    if (const toml::node* m = t.get("meshes")) {
      const auto& spec = pipeline_section();
      r.each_table(*m, "pipeline.meshes", spec, [&](const toml::table& e, const std::string& path) {
        const std::string kind = r.string(e, *spec.find("kind"), path);
        if (kind != "labels" && kind != "box" && kind != "stl" && kind != "fibres")
          r.fail(path + ".kind", "labels, box, stl or fibres", "\"" + kind + "\"");
        r.string(e, *spec.find("output"), path);
        r.string(e, *spec.find("args"), path);
        if (kind == "stl" && !e.contains("file")) r.fail(path + ".file", "the STL file of kind = stl", "missing");
        if (kind == "fibres" && !e.contains("file")) r.fail(path + ".file", "the mesh whose fibres kind = fibres makes", "missing");
        r.string(e, *spec.find("file"), path);
      });
    }
  }
}

void read_contact_solver(const Reader& r, const toml::table& root, Scenario& sc) {
  if (const toml::node* n = root.get("contact_solver")) {
    const auto& spec = contact_solver_section();
    const toml::table& t = r.table(*n, "contact_solver");
    r.check_keys(t, spec, "contact_solver");
    sc.contact_solver.tolerance = r.number(t, *spec.find("tolerance"), "contact_solver", 1e-6);
    sc.contact_solver.max_iterations = static_cast<int>(r.integer(t, *spec.find("max_iterations"), "contact_solver", 200));
    sc.contact_solver.search_factor = r.number(t, *spec.find("search_factor"), "contact_solver", 0.5);
    sc.contact_solver.pressure_window = r.number(t, *spec.find("pressure_window"), "contact_solver", 1e-5);
    sc.contact_solver.verlet_skin = r.number(t, *spec.find("verlet_skin"), "contact_solver", 0.5);
    sc.contact_solver.pressure_average_area = r.number(t, *spec.find("pressure_average_area"), "contact_solver", 25e-6);
    sc.contact_solver.recovery_speed = r.number(t, *spec.find("recovery_speed"), "contact_solver", 1.0);
    sc.contact_solver.sweep_blocks = static_cast<int>(r.integer(t, *spec.find("sweep_blocks"), "contact_solver", 16));
  }
}

}  // namespace

Scenario read_scenario(const fs::path& file, const fs::path& mesh_dir) {
  const std::string fname = file.string();
  require_regular_file(file, "a scenario (.toml)");
  toml::table root;
  try {
    root = toml::parse_file(fname);
  } catch (const toml::parse_error& e) {
    std::ostringstream where;
    where << "line " << e.source().begin.line << ", column " << e.source().begin.column;
    throw InputError(fname, where.str(), "valid TOML", std::string(e.description()));
  }
  Reader r(fname);
  Scenario sc;
  sc.file = fs::absolute(file);
  const fs::path base = mesh_dir.empty() ? sc.file.parent_path() : fs::absolute(mesh_dir);

  SectionSpec top{
      "",
      "",
      {typed("run", ValueType::table, "", "a [run] section", true), typed("damping", ValueType::table, "", "a [damping] section", false),
       typed("bodies", ValueType::table_list, "", "one or more [[bodies]] sections", true),
       typed("materials", ValueType::table, "", "[materials.<name>] sections", true),
       typed("boundary", ValueType::table_list, "", "[[boundary]] sections", false),
       typed("load", ValueType::table_list, "", "[[load]] sections", false), typed("curves", ValueType::table, "", "[curves.<name>] sections", false),
       typed("contact", ValueType::table_list, "", "[[contact]] sections", false),
       typed("contact_solver", ValueType::table, "", "a [contact_solver] section", false),
       typed("pipeline", ValueType::table, "", "a [pipeline] section with [[pipeline.meshes]] entries", false)}};
  r.check_keys(root, top, "");

  read_run(r, root, sc);
  read_damping(r, root, sc);
  read_materials(r, root, sc, fname);
  read_bodies(r, root, sc, base);
  read_curves(r, root, sc);
  read_boundaries(r, root, sc);
  read_loads(r, root, sc);
  read_contacts(r, root, sc);
  read_pipeline(r, root);
  read_contact_solver(r, root, sc);
  return sc;
}

std::string contact_method(const ContactSpec& c) {
  if (!c.method.empty()) return c.method;
  return c.plane || is_self_contact(c) || c.two_pass ? "node_to_surface" : "mortar";
}

bool is_self_contact(const ContactSpec& c) { return !c.plane && c.master_body == c.slave_body && c.master_surface == c.slave_surface; }

}  // namespace tactus::solver
