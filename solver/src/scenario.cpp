// scenario.toml reader. Every key is declared once, bound to the member it fills (scenario_keys.hpp):
// the same declarations validate the file and produce the key reference (`tactus-solve keys`), and
// each default shown there is the member's own initial value, so the docs cannot drift from what
// is accepted. What a single key cannot say (one of two keys, names of other sections) is checked
// after the section is read, below its declaration.
#include "tactus/solver/scenario.hpp"

#include <toml++/toml.h>
#include <cctype>
#include <charconv>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "scenario_keys.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/solver/material.hpp"

namespace fs = std::filesystem;

namespace tactus::solver {

using keys::bind_count;
using keys::bind_custom;
using keys::bind_key;
using keys::declare;
using keys::Reader;
using keys::Section;

namespace {

const std::vector<Choice<StepEstimate>>& step_estimates() {
  static const std::vector<Choice<StepEstimate>> c{
      {StepEstimate::nodal, "nodal",
       "the larger of the element estimate and a bound from each node's whole mass, which a badly shaped tet does not pull down"},
      {StepEstimate::element, "element", "the element-by-element estimate alone"}};
  return c;
}
const std::vector<Choice<BoundaryType>>& boundary_types() {
  static const std::vector<Choice<BoundaryType>> c{
      {BoundaryType::fixed, "fixed", ""}, {BoundaryType::velocity, "velocity", ""}, {BoundaryType::displacement, "displacement", ""}};
  return c;
}
const std::vector<Choice<ContactMethod>>& contact_methods() {
  static const std::vector<Choice<ContactMethod>> c{
      {ContactMethod::automatic, "automatic", "mortar; node_to_surface for self-contact, a rigid plane or two_pass"},
      {ContactMethod::node_to_surface, "node_to_surface", "each slave node on its closest master point"},
      {ContactMethod::mortar, "mortar",
       "segment-to-segment: each slave node's tributary surface integrated over the master triangles it overlaps, dual multipliers"}};
  return c;
}
const std::vector<Choice<MeshKind>>& mesh_kinds() {
  static const std::vector<Choice<MeshKind>> c{
      {MeshKind::labels, "labels", "from the segmented CT"},
      {MeshKind::box, "box", ""},
      {MeshKind::stl, "stl", ""},
      {MeshKind::fibres, "fibres", "rule-based hgo fibre directions of the mesh `file`: tactus-mesh fibres"},
      {MeshKind::skeleton, "skeleton", "the bones and joints of the hand mesh `file` (a .json): tactus-mesh skeleton"},
      {MeshKind::cylinder, "cylinder", "a cylinder of `radius` and `length`, with a `sleeve` over a core when > 0: tactus-mesh cylinder"}};
  return c;
}

const Section<RunSpec>& run_section() {
  static const Section<RunSpec> s{
      "run",
      "Time integration (explicit central differences, paper eq. 35) and output.",
      {bind_key(&RunSpec::end_time, keys::number("end_time", "s", "simulated end time", 0, true)),
       bind_key(&RunSpec::time_step_safety,
                keys::opt(keys::number("time_step_safety", "", "fraction of the critical step actually used", 0, true, 1))),
       bind_key(&RunSpec::time_step,
                keys::opt(keys::number("time_step", "s", "fixed user step; refused above the stable limit unless force_time_step", 0)), "automatic"),
       bind_key(&RunSpec::force_time_step, declare("force_time_step", "", "accept a user time_step above the stable limit")),
       bind_key(&RunSpec::step_estimate, declare("step_estimate", "", "the critical step"), step_estimates()),
       bind_key(&RunSpec::output_times,
                declare("output_times", "s", "times at which results are written, exactly (the state at end_time is always written too)")),
       bind_key(&RunSpec::output_interval, keys::opt(keys::number("output_interval", "s", "also write results at every k * interval", 0))),
       bind_key(&RunSpec::energy_tolerance,
                keys::opt(keys::number("energy_tolerance", "", "energy-balance error, relative to the largest energy, that stops the run as unstable",
                                       0, true))),
       bind_key(&RunSpec::gravity, declare("gravity", "m/s^2", "body acceleration")),
       bind_key(&RunSpec::gravity_ramp_time, keys::opt(keys::number("gravity_ramp_time", "s", "gravity grows linearly from 0 over this time", 0))),
       bind_key(&RunSpec::gravity_curve, declare("gravity_curve", "", "a [curves] name scaling gravity (instead of gravity_ramp_time)")),
       bind_key(&RunSpec::threads,
                keys::opt(keys::number("threads", "", "worker threads (0: all cores, at most one per ~4000 tets)", 0, false, 1024))),
       bind_key(&RunSpec::history_every,
                keys::opt(keys::number("history_every", "", "write a history row every N steps (0: about 2000 rows)", 0, false, 1e9))),
       bind_count(&RunSpec::max_outputs,
                  keys::opt(keys::number("max_outputs", "", "refuse schedules with more output states than this (a runaway guard)", 1, false, 1e9))),
       bind_count(&RunSpec::max_steps,
                  keys::opt(keys::number("max_steps", "", "refuse runs expected to take more steps than this (a runaway guard)", 1, false, 1e15))),
       bind_key(&RunSpec::minimum_time_step,
                keys::opt(keys::number("minimum_time_step", "s",
                                       "mass scaling: tets whose stable step (before the safety factor) falls below this get mass until it is met; "
                                       "the added mass is reported per body (0: off)",
                                       0)),
                "off"),
       bind_key(&RunSpec::added_mass_limit,
                keys::opt(keys::number("added_mass_limit", "", "stop the run when mass scaling has added more than this fraction of a body's mass", 0,
                                       true, 1))),
       bind_key(&RunSpec::checkpoint_interval,
                keys::opt(keys::number("checkpoint_interval", "s",
                                       "write a restart checkpoint every this much simulated time (and on an interrupt); tactus-solve --restart "
                                       "OUT continues a killed run from the newest (0: off)",
                                       0)),
                "off"),
       bind_key(
           &RunSpec::checkpoint_wall_interval,
           keys::opt(keys::number("checkpoint_wall_interval", "s", "also write a checkpoint every this many seconds of wall-clock time (0: off)", 0)),
           "off")}};
  return s;
}

const Section<DampingSpec>& damping_section() {
  static const Section<DampingSpec> s{
      "damping",
      "Rayleigh damping A = alpha M + beta K; the beta part is a viscous stress, never an assembled K.",
      {bind_key(&DampingSpec::alpha, keys::opt(keys::number("alpha", "1/s", "mass-proportional coefficient", 0))),
       bind_key(&DampingSpec::beta, keys::opt(keys::number("beta", "s", "stiffness-proportional coefficient", 0))),
       bind_key(&DampingSpec::adaptive, keys::declare("adaptive", "",
                                                      "dynamic relaxation: each step alpha = 2 omega, omega the frequency of the motion left "
                                                      "(the tangent stiffness's Rayleigh quotient along the step's velocity), at least alpha "
                                                      "above and at most 1 / dt: critical damping of the mode a relaxing body ends in")),
       bind_key(&DampingSpec::residual_tolerance,
                keys::opt(keys::number("residual_tolerance", "",
                                       "stop the run once the out-of-balance force on the free deformable nodes is "
                                       "at most this fraction of their internal force (after residual_after; under "
                                       "a [grasp] also with the grip within 1 % of its target); run.json "
                                       "relaxation says when",
                                       0, false, 1)),
                "0 (off)"),
       bind_key(&DampingSpec::residual_after, keys::opt(keys::number("residual_after", "s",
                                                                     "the earliest time the run may stop on residual_tolerance "
                                                                     "(after the loads have reached their final values)",
                                                                     0)))}};
  return s;
}

// "+x" .. "-z": the side of the other body a body is placed on.
std::string against_text(const BodySpec& b) { return std::string(b.against_side > 0 ? "+" : "-") + static_cast<char>('x' + b.against_axis); }

const Section<BodySpec>& body_section() {
  static const Section<BodySpec> s{
      "bodies",
      "[[bodies]]: one deformable body per entry.",
      {bind_key(&BodySpec::name, declare("name", "", "unique body name", true)),
       bind_key(&BodySpec::mesh, declare("mesh", "", "gmsh .msh file (relative to the scenario file)", true)),
       bind_key(&BodySpec::scale, keys::opt(keys::number("scale", "", "factor applied to mesh coordinates (1e-3 for a mesh in mm)", 0, true))),
       bind_key(&BodySpec::rotate_axis,
                declare("rotate_axis", "", "rotation axis (with rotate_angle; applied after scale, before translate and against)")),
       bind_key(&BodySpec::rotate_angle,
                keys::opt(keys::number("rotate_angle", "deg", "rotation angle about rotate_axis, right-handed", -360, false, 360))),
       bind_key(&BodySpec::rotate_matrix, declare("rotate_matrix", "", "rotation as a matrix, three rows (instead of rotate_axis and rotate_angle)")),
       bind_key(&BodySpec::rotate_about, declare("rotate_about", "m", "the point the rotation keeps fixed (scaled mesh coordinates)")),
       bind_key(&BodySpec::translate, declare("translate", "m", "translation applied after scaling")),
       bind_key(&BodySpec::initial_velocity, declare("initial_velocity", "m/s", "uniform initial velocity")),
       bind_key(
           &BodySpec::initial_angular_velocity,
           declare("initial_angular_velocity", "rad/s", "initial spin about the body's centre of mass: v = initial_velocity + w x (X - centre)")),
       bind_key(&BodySpec::rigid_velocity,
                declare("rigid_velocity", "m/s",
                        "prescribed velocity of the centre of each rigid piece of this body (materials of type rigid); with "
                        "rigid_angular_velocity, the pieces move as given and their reaction is reported (default: free rigid pieces)")),
       bind_key(&BodySpec::rigid_angular_velocity,
                declare("rigid_angular_velocity", "rad/s", "prescribed angular velocity of each rigid piece of this body, about its centre")),
       bind_key(&BodySpec::rigid_curve, declare("rigid_curve", "", "a [curves] name scaling rigid_velocity and rigid_angular_velocity")),
       bind_key(&BodySpec::rigid_guide,
                declare("rigid_guide", "",
                        "a direction (any length but 0): the body's free rigid pieces only translate along it and do not turn, as on a rail "
                        "whose reaction does no work (default: free in all six degrees of freedom)")),
       bind_key(&BodySpec::against, declare("against", "",
                                            "place this body next to an earlier body: after translate, it is moved along against_axis only, "
                                            "so that against_gap separates the two bounding boxes along that axis")),
       bind_custom<BodySpec>(
           declare("against_axis", "", "side of the other body this one lies on: +x, -x, +y, -y, +z or -z"), ValueType::string,
           [](const BodySpec& b) { return "\"" + against_text(b) + "\""; },
           [](const Reader& r, const ValueSpec& spec, const toml::table& t, const std::string& path, BodySpec& b) {
             const std::string axis = r.string(t, spec, path);
             if (axis.size() != 2 || (axis[0] != '+' && axis[0] != '-') || axis[1] < 'x' || axis[1] > 'z')
               r.fail(path + ".against_axis", "one of +x, -x, +y, -y, +z, -z", "\"" + axis + "\"");
             b.against_axis = axis[1] - 'x';
             b.against_side = axis[0] == '+' ? 1 : -1;
           }),
       bind_key(&BodySpec::against_gap, keys::opt(keys::number("against_gap", "m", "gap between the two bodies along against_axis", 0))),
       bind_key(&BodySpec::fibres, declare("fibres", "",
                                           "per-element hgo fibre directions: a .vtu of this mesh's tets with cell data fibre_1, fibre_2 "
                                           "(overrides the materials' constant fibres)")),
       bind_custom<BodySpec>(declare("materials", "", "physical volume group name -> material name (key \"*\" for every other group)", true),
                             ValueType::table, nullptr,
                             [](const Reader& r, const ValueSpec&, const toml::table& t, const std::string& path, BodySpec& b) {
                               for (const auto& [gk, gv] : r.table(*t.get("materials"), path + ".materials")) {
                                 const std::string group(gk.str());
                                 if (!gv.is_string()) r.fail(path + ".materials." + group, "a material name (string)", Reader::describe(gv));
                                 b.materials[group] = *gv.value<std::string>();
                               }
                             })}};
  return s;
}

const SectionSpec& material_common_section() {
  static const SectionSpec s{"materials.<name>",
                             "A named material; `type` selects the law, whose keys follow (see below, one section per law).",
                             {keys::with_default(declare("type", "", material_type_list(), true), ValueType::string, "", "")}};
  return s;
}

const Section<BoundarySpec>& boundary_section() {
  static const Section<BoundarySpec> s{
      "boundary",
      "[[boundary]]: fixed, prescribed-velocity or prescribed-displacement nodes of a body, by physical group or by box; "
      "its reaction force and moment are written in history.csv and run.json.",
      {bind_key(&BoundarySpec::body, declare("body", "", "body name", true)),
       bind_key(&BoundarySpec::group, declare("group", "", "physical surface or volume group whose nodes are constrained")),
       bind_key(&BoundarySpec::box, declare("box", "m", "[[xmin,ymin,zmin],[xmax,ymax,zmax]]: nodes inside (placed coordinates)"),
                "[[xmin, ymin, zmin], [xmax, ymax, zmax]]"),
       bind_key(&BoundarySpec::type, declare("type", "", "", true), boundary_types()),
       bind_key(&BoundarySpec::velocity, declare("velocity", "m/s", "prescribed velocity (type = velocity), times curve(t)")),
       bind_key(&BoundarySpec::displacement,
                declare("displacement", "m", "prescribed displacement (type = displacement), times curve(t), exact at every step")),
       bind_key(&BoundarySpec::curve, declare("curve", "", "a [curves] name scaling velocity or displacement (default: constant 1)")),
       bind_custom<BoundarySpec>(
           declare("components", "", "constrained components, any of \"xyz\""), ValueType::string,
           [](const BoundarySpec& bc) {
             std::string c;
             for (int i = 0; i < 3; ++i)
               if (bc.components[i]) c += static_cast<char>('x' + i);
             return "\"" + c + "\"";
           },
           [](const Reader& r, const ValueSpec& spec, const toml::table& t, const std::string& path, BoundarySpec& bc) {
             const std::string comps = r.string(t, spec, path);
             bc.components = {false, false, false};
             if (comps.empty()) r.fail(path + ".components", "one or more of x, y, z", "\"\"");
             for (char c : comps) {
               if (c < 'x' || c > 'z') r.fail(path + ".components", "letters among x, y, z", "\"" + comps + "\"");
               bc.components[c - 'x'] = true;
             }
           }),
       bind_key(&BoundarySpec::name, declare("name", "", "name of the reaction columns reaction_<name>_x.. (letters, digits, _)"), "boundary<k>"),
       bind_key(&BoundarySpec::moment_about, declare("moment_about", "m", "point the reaction moment is taken about"))}};
  return s;
}

const Section<LoadSpec>& load_section() {
  static const Section<LoadSpec> s{
      "load",
      "[[load]]: a follower pressure on a physical surface group of a body: normal to the current surface, on the current "
      "area, positive pushing into the body.",
      {bind_key(&LoadSpec::body, declare("body", "", "body name", true)),
       bind_key(&LoadSpec::group, declare("group", "", "physical surface group", true)),
       bind_key(&LoadSpec::type, declare("type", "", "", true), {{LoadType::pressure, "pressure", ""}}),
       bind_key(&LoadSpec::pressure, keys::number("pressure", "Pa", "pressure (times curve(t))")),
       bind_key(&LoadSpec::curve, declare("curve", "", "a [curves] name scaling the pressure (default: constant 1)"))}};
  return s;
}

const Section<CurveSpec>& curve_section() {
  static const Section<CurveSpec> s{
      "curves.<name>",
      "A named dimensionless factor of time for boundaries, loads and gravity: piecewise linear through (times, values), "
      "constant beyond the ends, or a smooth step from 0 to 1.",
      {bind_key(&CurveSpec::times, declare("times", "s", "increasing times of the table")),
       bind_key(&CurveSpec::values, declare("values", "", "the factor at each of times")),
       bind_custom<CurveSpec>(declare("smooth_step", "s", "[t0, t1]: 0 before t0, 1 after t1, 3s^2 - 2s^3 between (instead of a table)"),
                              ValueType::number_list, nullptr,
                              [](const Reader& r, const ValueSpec& spec, const toml::table& t, const std::string& path, CurveSpec& c) {
                                const auto ts = r.number_list(t, spec, path);
                                if (ts.size() != 2 || !(ts[1] > ts[0]))
                                  r.fail(path + ".smooth_step", "[t0, t1] with t1 > t0 >= 0", "an array of " + std::to_string(ts.size()));
                                c.smooth_step = true, c.t0 = ts[0], c.t1 = ts[1];
                              })}};
  return s;
}

const Section<ContactSpec>& contact_section() {
  static const Section<ContactSpec> s{
      "contact",
      "[[contact]]: bi-potential Coulomb contact (paper §2.1), slave nodes of one body's surface against "
      "another body's surface (master) or a rigid plane. The finer surface makes the better slave; against a rigid body (material type rigid) the "
      "deformable surface is the slave. A master equal to the slave "
      "(same body and surface) is self-contact: skin on skin, each node against the faces of the same surface that face it, "
      "its own neighbourhood excluded (node_to_surface, one pass).",
      {bind_key(&ContactSpec::slave_body, declare("slave_body", "", "body whose surface nodes are the slaves", true)),
       bind_key(&ContactSpec::slave_surface, declare("slave_surface", "", "physical surface group of slave_body (e.g. skin)", true)),
       bind_key(&ContactSpec::master_body, declare("master_body", "", "body owning the master surface (omit with plane)")),
       bind_key(&ContactSpec::master_surface, declare("master_surface", "", "physical surface group of master_body")),
       bind_key(&ContactSpec::plane, declare("plane", "m", "rigid plane master: [[point], [outward normal]] (instead of master_body)"),
                "[[x, y, z], [nx, ny, nz]]: a point and the outward normal"),
       bind_key(&ContactSpec::friction, keys::opt(keys::number("friction", "", "Coulomb friction coefficient mu", 0))),
       bind_key(&ContactSpec::two_pass, declare("two_pass", "", "also the master's nodes against the slave surface")),
       bind_key(&ContactSpec::edge_pass,
                declare("edge_pass", "",
                        "mortar: also the master's convex edge and corner nodes (faces meeting at more than 30 deg; not those "
                        "of rigid pieces) against the slave surface, node to surface, so a sharp master edge cannot cut into "
                        "the slave surface between its nodes")),
       bind_key(&ContactSpec::method, declare("method", "", "the contact discretisation"), contact_methods())}};
  return s;
}

const Section<ContactSettings>& contact_solver_section() {
  using S = ContactSettings;
  static const Section<S> s{
      "contact_solver",
      "Uzawa iterations of the bi-potential contact solver (Gauss-Seidel over the contact nodes).",
      {bind_key(&S::tolerance,
                keys::opt(keys::number("tolerance", "", "stop when max |dr| <= tolerance * max |r| over the contact nodes", 0, true, 1, true))),
       bind_key(&S::max_iterations,
                keys::opt(keys::number("max_iterations", "", "iteration limit per step (reached: a warning, the run goes on)", 1, false, 1e6))),
       bind_key(&S::search_factor,
                keys::opt(keys::number("search_factor", "", "search distance and penetration band, in mean master edge lengths", 0, true, 10))),
       bind_key(&S::verlet_skin,
                keys::opt(keys::number("verlet_skin", "",
                                       "node-to-surface search: candidate triangles are gathered within the band plus this skin (in mean master "
                                       "edge lengths) and kept until a node has moved half the skin (0: search every step)",
                                       0, false, 10))),
       bind_key(&S::pressure_window,
                keys::opt(keys::number("pressure_window", "s",
                                       "the reported contact pressure is r_n / A averaged over an exponential window of max(this, 10 initial "
                                       "critical steps), so an impact's peak does not grow like 1/dt",
                                       0, true))),
       bind_key(&S::pressure_average_area,
                keys::opt(keys::number("pressure_average_area", "m^2",
                                       "at each output the contact pressure field is also averaged over discs of this area on the slave surfaces, "
                                       "and the largest average is reported (run.json contact.at_outputs), a peak that converges with the mesh",
                                       0, true))),
       bind_key(&S::recovery_speed,
                keys::opt(keys::number("recovery_speed", "m/s",
                                       "a node found inside its master deeper than this speed times the step (a penetration the previous step did "
                                       "not make, e.g. a node sliding back over a master's edge) is pushed out at this speed rather than in one "
                                       "step, which would give it depth / dt (run.json contact.uzawa.recovering_rows counts them)",
                                       0, true))),
       bind_key(&S::sweep_blocks,
                keys::opt(keys::number("sweep_blocks", "",
                                       "the Uzawa sweep is cut into at most this many slabs along the contact (at most one per 256 rows), the even "
                                       "ones swept in parallel, then the odd ones, then the rows they share in order; the same bits on any thread "
                                       "count; 1: one Gauss-Seidel sweep in row order",
                                       1, false, 4096)))}};
  return s;
}

const Section<MeshPlanEntry>& pipeline_section() {
  static const Section<MeshPlanEntry> s{
      "pipeline.meshes",
      "[[pipeline.meshes]]: how tactus-pipeline makes each mesh this scenario uses (tactus-solve checks these entries and "
      "prints them with `tactus-solve mesh-plan`; the pipeline runs tactus-mesh for them).",
      {bind_key(&MeshPlanEntry::output,
                declare("output", "",
                        "the mesh file (or, kind = fibres, the fibre file) a [[bodies]] entry names, relative to the pipeline's work folder", true)),
       bind_key(&MeshPlanEntry::kind, declare("kind", "", "", true), mesh_kinds()),
       bind_key(&MeshPlanEntry::args, declare("args", "", "tactus-mesh options (e.g. \"--size 0.04 0.08 0.16 --element-size 0.008\")"), "none"),
       bind_key(&MeshPlanEntry::file, declare("file", "",
                                              "kind = stl: the closed STL surface, relative to the scenario's folder; kind = fibres: the mesh, "
                                              "relative to the work folder")),
       bind_key(&MeshPlanEntry::radius, keys::opt(keys::number("radius", "m", "kind = cylinder (required): the outer radius", 0, true)), "none"),
       bind_key(&MeshPlanEntry::length, keys::opt(keys::number("length", "m", "kind = cylinder (required): the length", 0, true)), "none"),
       bind_key(&MeshPlanEntry::sleeve,
                keys::opt(keys::number("sleeve", "m",
                                       "kind = cylinder: a deformable sleeve of this thickness over a core (volume groups \"core\" and "
                                       "\"sleeve\"; 0 or none: one volume \"object\")",
                                       0)),
                "none")}};
  return s;
}

}  // namespace

const char* boundary_type_name(BoundaryType t) {
  return t == BoundaryType::fixed ? "fixed" : t == BoundaryType::velocity ? "velocity" : "displacement";
}
const char* mesh_kind_name(MeshKind k) {
  switch (k) {
    case MeshKind::labels:
      return "labels";
    case MeshKind::box:
      return "box";
    case MeshKind::stl:
      return "stl";
    case MeshKind::fibres:
      return "fibres";
    case MeshKind::skeleton:
      return "skeleton";
    case MeshKind::cylinder:
      return "cylinder";
  }
  return "";
}

const Section<SkeletonSpec>& skeleton_section() {
  static const Section<SkeletonSpec> s{
      "skeleton",
      "[skeleton]: the bones of one body and the joints between them, for [[joint]] and [grasp] to move. Each bone is the body's "
      "rigid piece meshed from its label; it moves by forward kinematics down its chain, the soft tissue following through the "
      "nodes it shares with the bones. The roots (carpals) are held.",
      {bind_key(&SkeletonSpec::body, declare("body", "", "the body whose bones the skeleton names", true)),
       bind_key(&SkeletonSpec::file, declare("file", "",
                                             "skeleton.json (tactus-mesh skeleton, or tactus-phantom's joints.json), in the "
                                             "body's mesh frame before its placement (relative to the scenario file)",
                                             true))}};
  return s;
}

const Section<JointSpec>& joint_section() {
  static const Section<JointSpec> s{
      "joint",
      "[[joint]]: one joint's angles added to the mesh's posture, angle x curve(t); a joint with an entry moves by it, "
      "not by the grasp's torque.",
      {bind_key(&JointSpec::name, declare("name", "", "a joint of the skeleton (mcp_index, pip_middle, ip_thumb, ...)", true)),
       bind_key(&JointSpec::flexion, keys::opt(keys::number("flexion", "deg", "flexion towards the palm", -180, false, 180))),
       bind_key(&JointSpec::abduction, keys::opt(keys::number("abduction", "deg", "abduction about the joint's abduction axis", -180, false, 180))),
       bind_key(&JointSpec::curve, declare("curve", "", "a [curves] name scaling both angles; it starts at 0 (a posture cannot jump)", true))}};
  return s;
}

const Section<GraspSpec>& grasp_section() {
  static const Section<GraspSpec> s{
      "grasp",
      "[grasp]: a torque-driven grip. Every joint no [[joint]] drives gets the flexion torque s(t) x its kind's weight; s comes "
      "from a PI loop on the total grip force (the normal contact forces between the handle and the other bodies) against "
      "the target, ramped from 0 over ramp_time and then held.",
      {bind_key(&GraspSpec::handle, declare("handle", "", "the body the hand grips (its [[contact]] entries give the grip force)", true)),
       bind_key(&GraspSpec::target_force, keys::number("target_force", "N", "grip force to reach and hold", 0, true)),
       bind_key(&GraspSpec::ramp_time, keys::opt(keys::number("ramp_time", "s", "the target rises linearly from 0 over this time", 0))),
       bind_key(&GraspSpec::gain_p, keys::opt(keys::number("gain_p", "m", "proportional gain: N m of drive per N of grip error", 0))),
       bind_key(&GraspSpec::gain_i, keys::opt(keys::number("gain_i", "m/s", "integral gain: N m of drive per N s of grip error", 0))),
       bind_key(&GraspSpec::max_torque, keys::opt(keys::number("max_torque", "N m", "the largest drive s (weight 1)", 0, true))),
       bind_key(&GraspSpec::flexion_min, keys::opt(keys::number("flexion_min", "deg", "each torque-driven joint's extension stop", -90, false, 0))),
       bind_key(&GraspSpec::flexion_max, keys::opt(keys::number("flexion_max", "deg", "each torque-driven joint's flexion stop", 0, true, 150))),
       bind_key(&GraspSpec::weight_mcp, keys::opt(keys::number("weight_mcp", "", "torque weight of a finger's MCP joint", 0))),
       bind_key(&GraspSpec::weight_pip, keys::opt(keys::number("weight_pip", "", "of a finger's PIP joint", 0))),
       bind_key(&GraspSpec::weight_dip, keys::opt(keys::number("weight_dip", "", "of a finger's DIP joint", 0))),
       bind_key(&GraspSpec::weight_cmc, keys::opt(keys::number("weight_cmc", "", "of a finger's CMC joint (0: held)", 0))),
       bind_key(&GraspSpec::weight_thumb_cmc, keys::opt(keys::number("weight_thumb_cmc", "", "of the thumb's CMC joint", 0))),
       bind_key(&GraspSpec::weight_thumb_mcp, keys::opt(keys::number("weight_thumb_mcp", "", "of the thumb's MCP joint", 0))),
       bind_key(&GraspSpec::weight_thumb_ip, keys::opt(keys::number("weight_thumb_ip", "", "of the thumb's IP joint", 0))),
       bind_key(&GraspSpec::handle_centre,
                declare("handle_centre", "m",
                        "[across, along, out]: the handle's bounding-box centre moved to this point of the skeleton's palm frame (origin the "
                        "mean of the fingers' MCP joint centres, along their metacarpals, out of the palm), its longest side turned across "
                        "the palm (default: the handle stays where its [[bodies]] keys put it)")),
       bind_key(&GraspSpec::handle_guided,
                declare("handle_guided", "",
                        "true: the handle (free, no rigid_velocity) only moves along the palm frame's normal and does not turn, as a grip "
                        "dynamometer's handle: the palm then reacts what the fingers squeeze (default false: a free handle is free in all "
                        "six degrees of freedom)"))}};
  return s;
}

std::vector<SectionSpec> scenario_reference() {
  std::vector<SectionSpec> out{
      run_section().spec(),      damping_section().spec(), body_section().spec(),    material_common_section(),       curve_section().spec(),
      boundary_section().spec(), load_section().spec(),    contact_section().spec(), contact_solver_section().spec(), pipeline_section().spec(),
      skeleton_section().spec(), joint_section().spec(),   grasp_section().spec()};
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
      o << "| `" << k.key << "` | " << keys::type_name(k.type) << " | " << (k.unit.empty() ? "-" : k.unit) << " | "
        << (k.range_text().empty() ? "-" : k.range_text()) << " | " << (k.required ? "**required**" : (k.default_text.empty() ? "-" : k.default_text))
        << " | " << k.doc << " |\n";
    }
  }
  return o.str();
}

namespace {

// The sections of scenario.toml, one reader each (called in this order by read_scenario): the
// bound keys, then what no single key can say.
void read_run(const Reader& r, const toml::table& root, Scenario& sc) {
  RunSpec& run = sc.run;
  run_section().read(r, r.table(*root.get("run"), "run"), "run", run);
  if (!run.gravity_curve.empty() && run.gravity_ramp_time > 0) r.fail("run", "either gravity_ramp_time or gravity_curve", "both");
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

void read_damping(const Reader& r, const toml::table& root, Scenario& sc) {
  if (const toml::node* n = root.get("damping")) damping_section().read(r, r.table(*n, "damping"), "damping", sc.damping);
}

void read_materials(const Reader& r, const toml::table& root, Scenario& sc, const std::string& fname) {
  // [materials.<name>]: validated against the law's own declarations (material.hpp)
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
      if (ps.type == ValueType::number && (ps.required || t.contains(ps.key)))  // an optional one absent: the law's default
        m.values.numbers[ps.key] = r.number(t, ps, path, 0);
      else if (ps.type == ValueType::vec3_list && t.contains(ps.key))
        m.values.vectors[ps.key] = r.vec3_list(t, ps, path);
      else if (ps.type == ValueType::string && t.contains(ps.key))
        m.values.strings[ps.key] = r.string(t, ps, path);
      else if (ps.type == ValueType::integer && t.contains(ps.key))
        m.values.numbers[ps.key] = static_cast<double>(r.integer(t, ps, path));
    }
    m.values.source = fname;
    sc.laws[name] = Material::make(m.type, m.values, path);  // with the law's own checks (hgo: two non-zero fibre directions)
    sc.materials[name] = m;
  }
}

// rotate_axis + rotate_angle (Rodrigues' formula) or rotate_matrix (checked orthonormal, det +1).
void resolve_rotation(const Reader& r, const toml::table& t, const std::string& path, BodySpec& b) {
  const bool by_axis = t.contains("rotate_axis") || t.contains("rotate_angle"), by_matrix = t.contains("rotate_matrix");
  if (by_axis && by_matrix) r.fail(path + ".rotate_matrix", "either rotate_matrix or rotate_axis + rotate_angle", "both");
  if (by_axis) {
    if (!t.contains("rotate_axis") || !t.contains("rotate_angle"))
      r.fail(path + ".rotate_axis", "rotate_axis and rotate_angle together", "one of them");
    const Vec3 a = *b.rotate_axis;
    const double n = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (!(n > 0)) r.fail(path + ".rotate_axis", "a non-zero axis", "[0, 0, 0]");
    const double th = b.rotate_angle * M_PI / 180.0;
    const double x = a[0] / n, y = a[1] / n, z = a[2] / n, c = std::cos(th), s = std::sin(th), C = 1 - c;
    b.rotation = {Vec3{c + x * x * C, x * y * C - z * s, x * z * C + y * s}, Vec3{y * x * C + z * s, c + y * y * C, y * z * C - x * s},
                  Vec3{z * x * C - y * s, z * y * C + x * s, c + z * z * C}};
    b.rotated = true;
  } else if (by_matrix) {
    const auto& rows = b.rotate_matrix;
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
  const toml::array* arr = root.get("bodies")->as_array();
  if (arr && arr->empty()) r.fail("bodies", "one or more [[bodies]] tables", "none");
  std::set<std::string> names;
  r.each_table(*root.get("bodies"), "bodies", [&](const toml::table& t, const std::string& path) {
    BodySpec b;
    body_section().read(r, t, path, b);
    if (!names.insert(b.name).second) r.fail(path + ".name", "a unique body name", "\"" + b.name + "\" twice");
    b.mesh = base / b.mesh;
    resolve_rotation(r, t, path, b);
    if (b.rigid_velocity || b.rigid_angular_velocity) {
      if (!b.rigid_velocity) b.rigid_velocity = Vec3{0, 0, 0};
      if (!b.rigid_angular_velocity) b.rigid_angular_velocity = Vec3{0, 0, 0};
    } else if (t.contains("rigid_curve")) {
      r.fail(path + ".rigid_curve", "rigid_velocity or rigid_angular_velocity with it", "a curve alone");
    }
    if (b.rigid_guide && (b.rigid_velocity || !(norm(*b.rigid_guide) > 0)))
      r.fail(path + ".rigid_guide", "a direction of non-zero length on a body whose rigid pieces are free (no rigid_velocity)",
             b.rigid_velocity ? "a prescribed body" : "a zero vector");
    if (!b.fibres.empty()) b.fibres = base / b.fibres;
    if (t.contains("against")) {
      if (!names.count(b.against) || b.against == b.name)
        r.fail(path + ".against", "the name of a [[bodies]] entry listed before this one", "\"" + b.against + "\"");
    } else if (t.contains("against_axis") || t.contains("against_gap")) {
      r.fail(path + ".against", "the body to place against (against_axis and against_gap need it)", "missing");
    }
    for (const auto& [group, mat] : b.materials) {
      if (sc.materials.count(mat)) continue;
      std::string known;
      for (const auto& [n, m] : sc.materials) known += (known.empty() ? "" : ", ") + n;
      r.fail(path + ".materials." + group, "a material defined under [materials] (" + known + ")", "\"" + mat + "\"");
    }
    sc.bodies.push_back(b);
  });
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
    for (const auto& [k, node] : r.table(*n, "curves")) {
      const std::string name(k.str()), path = "curves." + name;
      CurveSpec c;
      c.name = name;
      const toml::table& t = r.table(node, path);
      curve_section().read(r, t, path, c);
      if (c.smooth_step) {
        if (t.contains("times") || t.contains("values")) r.fail(path, "either times + values or smooth_step", "both");
      } else {
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
    r.each_table(*n, "load", [&](const toml::table& t, const std::string& path) {
      LoadSpec l;
      load_section().read(r, t, path, l);
      require_body(r, sc, l.body, path + ".body");
      require_curve(r, sc, l.curve, path + ".curve");
      sc.loads.push_back(l);
    });
  }
}

void read_boundaries(const Reader& r, const toml::table& root, Scenario& sc) {
  if (const toml::node* n = root.get("boundary")) {  // [[boundary]]
    r.each_table(*n, "boundary", [&](const toml::table& t, const std::string& path) {
      BoundarySpec bc;
      bc.name = "boundary" + std::to_string(sc.boundaries.size());
      boundary_section().read(r, t, path, bc);
      require_body(r, sc, bc.body, path + ".body");
      if (bc.group.empty() == !bc.box.has_value()) r.fail(path, "exactly one of `group` or `box`");
      const std::string type = boundary_type_name(bc.type);
      if (t.contains("velocity") && bc.type != BoundaryType::velocity)
        r.fail(path + ".velocity", "type = \"velocity\" with a velocity", "type \"" + type + "\"");
      if (t.contains("displacement") && bc.type != BoundaryType::displacement)
        r.fail(path + ".displacement", "type = \"displacement\" with a displacement", "type \"" + type + "\"");
      if (!bc.curve.empty() && bc.type == BoundaryType::fixed)
        r.fail(path + ".curve", "a curve only for type velocity or displacement", "type \"fixed\"");
      require_curve(r, sc, bc.curve, path + ".curve");
      require_column_name(r, sc, bc.name, path + ".name");
      sc.boundaries.push_back(bc);
    });
  }
}

void read_contacts(const Reader& r, const toml::table& root, Scenario& sc) {
  if (const toml::node* n = root.get("contact")) {  // [[contact]]
    r.each_table(*n, "contact", [&](const toml::table& t, const std::string& path) {
      ContactSpec c;
      contact_section().read(r, t, path, c);
      require_body(r, sc, c.slave_body, path + ".slave_body");
      if (c.plane) {
        const Vec3& normal = (*c.plane)[1];
        if (!(std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]) > 0))
          r.fail(path + ".plane", "a non-zero normal", "zero vector");
        if (t.contains("master_body") || t.contains("master_surface")) r.fail(path, "either `plane` or `master_body` + `master_surface`", "both");
      } else {
        if (c.master_body.empty() || c.master_surface.empty()) r.fail(path, "`master_body` and `master_surface` (or a rigid `plane`)", "missing");
        require_body(r, sc, c.master_body, path + ".master_body");
      }
      if (is_self_contact(c)) {
        const std::string what = "\"" + c.slave_body + "/" + c.slave_surface + "\" against itself (self-contact)";
        if (c.method == ContactMethod::mortar) r.fail(path + ".method", "node_to_surface for self-contact", what + " with mortar");
        if (c.two_pass) r.fail(path + ".two_pass", "false for self-contact (every node of the surface is already a slave)", what + " with two_pass");
      }
      if (c.method == ContactMethod::mortar && c.plane)
        r.fail(path + ".method", "node_to_surface for a rigid plane (it has no surface to integrate over)", "mortar");
      if (c.two_pass && c.plane) r.fail(path + ".two_pass", "false for a rigid plane", "true");
      if (c.two_pass && c.method == ContactMethod::mortar)
        r.fail(path + ".two_pass", "false with mortar (its rows already weigh the master's nodes)", "true");
      if (t.contains("edge_pass") && c.edge_pass && contact_method(c) != ContactMethod::mortar)
        r.fail(path + ".edge_pass",
               "true only with mortar (node to surface has two_pass; self-contact and a rigid plane have no master edges to add)",
               std::string("true with ") + contact_method_name(contact_method(c)));
      sc.contacts.push_back(c);
    });
  }
}

// A relative path that stays inside the folder it is relative to.
bool inside_work_folder(const std::string& p) {
  if (p.empty() || fs::path(p).is_absolute()) return false;
  for (const auto& part : fs::path(p))
    if (part == "..") return false;
  return true;
}

void read_pipeline(const Reader& r, const toml::table& root, Scenario& sc) {
  if (const toml::node* n = root.get("pipeline")) {  // checked here, used by tactus-pipeline (tactus-solve mesh-plan)
    const toml::table& t = r.table(*n, "pipeline");
    r.check_keys(
        t, SectionSpec{"pipeline", "", {keys::with_default(declare("meshes", "", "[[pipeline.meshes]] entries"), ValueType::table_list, "", "")}},
        "pipeline");
    if (const toml::node* m = t.get("meshes")) {
      r.each_table(*m, "pipeline.meshes", [&](const toml::table& e, const std::string& path) {
        MeshPlanEntry entry;
        pipeline_section().read(r, e, path, entry);
        const std::string ext = entry.kind == MeshKind::fibres ? ".vtu" : entry.kind == MeshKind::skeleton ? ".json" : ".msh";
        if (!inside_work_folder(entry.output) || fs::path(entry.output).extension() != ext)
          r.fail(path + ".output", "a " + ext + " path inside the work folder", "\"" + entry.output + "\"");
        if (entry.kind == MeshKind::stl && entry.file.empty()) r.fail(path + ".file", "the STL file of kind = stl", "missing");
        const bool cylinder = entry.kind == MeshKind::cylinder;
        if (cylinder && !entry.radius) r.fail(path + ".radius", "the radius of kind = cylinder", "missing");
        if (cylinder && !entry.length) r.fail(path + ".length", "the length of kind = cylinder", "missing");
        if (cylinder && entry.sleeve && !(*entry.sleeve < *entry.radius))
          r.fail(path + ".sleeve", "a thickness less than the radius (" + std::to_string(*entry.radius) + " m)", std::to_string(*entry.sleeve));
        if (!cylinder && (entry.radius || entry.length || entry.sleeve))
          r.fail(path + (entry.radius   ? ".radius"
                         : entry.length ? ".length"
                                        : ".sleeve"),
                 "radius, length and sleeve only with kind = cylinder", std::string("kind = ") + mesh_kind_name(entry.kind));
        if ((entry.kind == MeshKind::fibres || entry.kind == MeshKind::skeleton) && !inside_work_folder(entry.file))
          r.fail(path + ".file",
                 "the mesh whose " + std::string(mesh_kind_name(entry.kind)) + " this entry makes (a .msh path inside the work folder)",
                 "\"" + entry.file + "\"");
        sc.mesh_plan.push_back(entry);
      });
    }
  }
}

// [skeleton], [[joint]] and [grasp]: the joints need the skeleton, the grasp its handle.
void read_joints(const Reader& r, const toml::table& root, Scenario& sc, const fs::path& base) {
  if (const toml::node* n = root.get("skeleton")) {
    SkeletonSpec spec;
    skeleton_section().read(r, r.table(*n, "skeleton"), "skeleton", spec);
    require_body(r, sc, spec.body, "skeleton.body");
    spec.file = base / spec.file;
    sc.skeleton = spec;
  }
  if (const toml::node* n = root.get("joint")) {
    if (!sc.skeleton) r.fail("joint", "a [skeleton] for the [[joint]] entries to name joints of", "none");
    std::set<std::string> names;
    r.each_table(*n, "joint", [&](const toml::table& t, const std::string& path) {
      JointSpec j;
      joint_section().read(r, t, path, j);
      require_curve(r, sc, j.curve, path + ".curve");
      if (!names.insert(j.name).second) r.fail(path + ".name", "one [[joint]] entry per joint", "\"" + j.name + "\" twice");
      sc.joints.push_back(j);
    });
  }
  if (const toml::node* n = root.get("grasp")) {
    if (!sc.skeleton) r.fail("grasp", "a [skeleton] whose joints the grasp drives", "none");
    grasp_section().read(r, r.table(*n, "grasp"), "grasp", sc.grasp);
    require_body(r, sc, sc.grasp.handle, "grasp.handle");
    if (sc.grasp.handle == sc.skeleton->body) r.fail("grasp.handle", "a body other than the hand", "\"" + sc.grasp.handle + "\"");
  }
}

void read_contact_solver(const Reader& r, const toml::table& root, Scenario& sc) {
  if (const toml::node* n = root.get("contact_solver"))
    contact_solver_section().read(r, r.table(*n, "contact_solver"), "contact_solver", sc.contact_solver);
}

// One --set KEY=VALUE over the parsed file: KEY walks tables by name and [[...]] lists by 0-based
// index; the last name is set (added when the file leaves it out, so an optional key can be
// studied). VALUE is read as TOML (0.02, 3, true, [1, 2], "text"); a bare word is a string.
void apply_override(toml::table& root, const std::string& item) {
  const auto fail = [&](const std::string& expected, const std::string& found) {
    throw InputError("command line", "--set " + item, expected, found);
  };
  const std::size_t eq = item.find('=');
  if (eq == std::string::npos || eq == 0) fail("KEY=VALUE (e.g. grasp.target_force=30)", "no '='");
  std::vector<std::string> path;
  std::istringstream keys(item.substr(0, eq));
  for (std::string k; std::getline(keys, k, '.');) path.push_back(k);
  const std::string text = item.substr(eq + 1);
  toml::table value_doc;
  try {
    value_doc = toml::parse("v = " + text);
  } catch (const toml::parse_error&) {
    value_doc.insert_or_assign("v", text);
  }
  toml::node* node = &root;
  std::string walked;
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const std::string& k = path[i];
    toml::node* next = nullptr;
    if (toml::array* a = node->as_array()) {
      std::size_t index = 0;
      const auto [end, ec] = std::from_chars(k.data(), k.data() + k.size(), index);
      if (ec != std::errc() || end != k.data() + k.size() || index >= a->size())
        fail("an index from 0 to " + std::to_string(a->size() - 1) + " into " + walked + " (its entries in file order)", "\"" + k + "\"");
      next = a->get(index);
    } else if (toml::table* t = node->as_table()) {
      next = t->get(k);
      if (!next) fail("a section or list the scenario has", "no " + (walked.empty() ? "" : walked + ".") + k + " in the file");
    }
    if (!next || !(next->is_table() || next->is_array()))
      fail("a path through sections and lists", (walked.empty() ? "" : walked + ".") + k + " is a value");
    walked += (walked.empty() ? "" : ".") + k;
    node = next;
  }
  toml::table* t = node->as_table();
  if (!t || path.back().empty()) fail("a key of a section", walked.empty() ? "an empty key" : walked + " is a list; give an entry's index");
  t->insert_or_assign(path.back(), *value_doc.get("v"));
}

}  // namespace

Scenario read_scenario(const fs::path& file, const fs::path& mesh_dir, const std::vector<std::string>& overrides) {
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
  for (const std::string& item : overrides) apply_override(root, item);
  Reader r(fname);
  Scenario sc;
  sc.file = fs::absolute(file);
  sc.overrides = overrides;
  const fs::path base = mesh_dir.empty() ? sc.file.parent_path() : fs::absolute(mesh_dir);

  auto section = [](std::string key, ValueType type, std::string doc, bool required) {
    return keys::with_default(declare(std::move(key), "", std::move(doc), required), type, "", "");
  };
  const SectionSpec top{
      "",
      "",
      {section("run", ValueType::table, "a [run] section", true), section("damping", ValueType::table, "a [damping] section", false),
       section("bodies", ValueType::table_list, "one or more [[bodies]] sections", true),
       section("materials", ValueType::table, "[materials.<name>] sections", true),
       section("boundary", ValueType::table_list, "[[boundary]] sections", false), section("load", ValueType::table_list, "[[load]] sections", false),
       section("curves", ValueType::table, "[curves.<name>] sections", false),
       section("contact", ValueType::table_list, "[[contact]] sections", false),
       section("contact_solver", ValueType::table, "a [contact_solver] section", false),
       section("pipeline", ValueType::table, "a [pipeline] section with [[pipeline.meshes]] entries", false),
       section("skeleton", ValueType::table, "a [skeleton] section", false), section("joint", ValueType::table_list, "[[joint]] sections", false),
       section("grasp", ValueType::table, "a [grasp] section", false)}};
  r.check_keys(root, top, "");

  read_run(r, root, sc);
  read_damping(r, root, sc);
  read_materials(r, root, sc, fname);
  read_bodies(r, root, sc, base);
  read_curves(r, root, sc);
  read_boundaries(r, root, sc);
  read_loads(r, root, sc);
  read_contacts(r, root, sc);
  read_pipeline(r, root, sc);
  read_contact_solver(r, root, sc);
  read_joints(r, root, sc, base);
  return sc;
}

namespace {
// The shortest decimal text that reads back as exactly x (0.015, not 0.014999999999999999).
std::string shortest_text(double x) {
  char text[32];
  const auto [end, ec] = std::to_chars(text, text + sizeof text, x);
  return ec == std::errc() ? std::string(text, end) : std::to_string(x);
}
}  // namespace

std::string mesh_plan_json(const Scenario& sc) {
  nlohmann::json plan{{"meshes", nlohmann::json::array()}, {"inputs", nlohmann::json::array()}};
  for (const MeshPlanEntry& m : sc.mesh_plan) {
    std::string args = m.args;
    if (m.kind == MeshKind::cylinder)  // its own keys first, as tactus-mesh cylinder options
      args = "--radius " + shortest_text(*m.radius) + " --length " + shortest_text(*m.length) + " --sleeve " + shortest_text(m.sleeve.value_or(0.0)) +
             (args.empty() ? "" : " " + args);
    plan["meshes"].push_back({{"output", m.output}, {"kind", mesh_kind_name(m.kind)}, {"args", args}, {"file", m.file}});
  }
  for (const BodySpec& b : sc.bodies) {
    plan["inputs"].push_back(b.mesh.string());
    if (!b.fibres.empty()) plan["inputs"].push_back(b.fibres.string());
  }
  if (sc.skeleton) plan["inputs"].push_back(sc.skeleton->file.string());
  return plan.dump(2) + "\n";
}

}  // namespace tactus::solver
