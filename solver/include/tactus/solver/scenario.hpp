#pragma once
// scenario.toml: what to simulate. Every key is declared (parameters.hpp) with unit and range;
// unknown keys, missing required keys and out-of-range values are errors naming the key.
// Lengths m, times s, velocities m/s, stresses Pa, densities kg/m^3.
#include <array>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "tactus/core/vec3.hpp"
#include "tactus/solver/material.hpp"
#include "tactus/solver/parameters.hpp"

namespace tactus::solver {

// The critical step: the larger of the element estimate and a bound from each node's whole mass
// (nodal), or the element estimate alone (element; what explicit codes call element-by-element).
// design.md "The stable step".
enum class StepEstimate { nodal, element };

struct RunSpec {
  double end_time = 0;
  double time_step_safety = 0.9;
  double time_step = 0;          // 0: automatic (safety x critical step)
  bool force_time_step = false;  // accept a user time_step above the stable limit
  StepEstimate step_estimate = StepEstimate::nodal;
  std::vector<double> output_times;
  double output_interval = 0;
  double energy_tolerance = 0.25;  // relative energy-balance error that stops a run as unstable
  Vec3 gravity{0, 0, 0};
  double gravity_ramp_time = 0;
  std::string gravity_curve;   // [curves] name scaling gravity (empty: the linear ramp above, or constant)
  int threads = 0;             // 0: all cores
  int history_every = 0;       // 0: automatic (about 2000 rows)
  double max_outputs = 10000;  // runaway guards: refused above these
  double max_steps = 1e7;
  // Mass scaling: tets whose stable step falls below minimum_time_step get mass until it is met
  // (0: off); the run stops when a body's added mass exceeds added_mass_limit of its mass.
  double minimum_time_step = 0;
  double added_mass_limit = 0.01;
  // Restart checkpoints (checkpoint.hpp): every checkpoint_interval of simulated time and every
  // checkpoint_wall_interval of wall-clock time (0: off), and on an interrupt when either is on.
  double checkpoint_interval = 0, checkpoint_wall_interval = 0;
  bool checkpoints() const { return checkpoint_interval > 0 || checkpoint_wall_interval > 0; }
};

struct DampingSpec {
  double alpha = 0;  // 1/s, mass-proportional
  double beta = 0;   // s, stiffness-proportional (evaluated as a viscous stress)
};

struct MaterialInstance {
  std::string name, type;
  MaterialValues values;  // validated against the law's declarations
};

// [curves.<name>]: a dimensionless factor of time that scales a boundary value, a load or gravity.
struct CurveSpec {
  std::string name;
  std::vector<double> times, values;  // piecewise linear through (times[k], values[k]), constant beyond the ends
  bool smooth_step = false;           // instead: 0 before t0, 1 after t1, 3s^2 - 2s^3 between (s = (t - t0)/(t1 - t0))
  double t0 = 0, t1 = 0;
  double at(double t) const;
  // The integral from 0 to t (the displacement of a velocity scaled by this curve), exact.
  double integral(double t) const;
};

struct BodySpec {
  std::string name;
  std::filesystem::path mesh;
  double scale = 1.0;  // applied to mesh coordinates before translate (e.g. 1e-3 for mm meshes)
  // Rotation after scaling, before translate and against: x -> R (x - about) + about. Identity
  // unless the scenario gives rotate_axis + rotate_angle or rotate_matrix. Fibre directions rotate
  // with the body.
  std::array<Vec3, 3> rotation{Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};  // rows of R
  Vec3 rotate_about{0, 0, 0};
  bool rotated = false;
  // As given (the reader turns them into `rotation`): an axis and an angle, or a matrix's rows.
  std::optional<Vec3> rotate_axis;
  double rotate_angle = 0;  // deg
  std::vector<Vec3> rotate_matrix;
  Vec3 translate{0, 0, 0};
  Vec3 initial_velocity{0, 0, 0};
  Vec3 initial_angular_velocity{0, 0, 0};  // rad/s about the body's centre of mass: v = v0 + w x (X - c)
  // Its rigid pieces' prescribed motion (rigid.hpp); either given: prescribed.
  std::optional<Vec3> rigid_velocity, rigid_angular_velocity;
  std::string rigid_curve;
  std::filesystem::path fibres;  // optional .vtu with per-tet cell data fibre_1, fibre_2
  // Placement against an earlier body: moved along one axis to leave against_gap between the
  // bounding boxes (e.g. the block 0.5 mm from the hand, whatever the hand mesh).
  std::string against;
  int against_axis = 0, against_side = 1;  // x, y, z = 0, 1, 2; +1: on the other body's high side
  double against_gap = 0;
  std::map<std::string, std::string> materials;  // physical volume name (or "*") -> material
};

enum class BoundaryType { fixed, velocity, displacement };
const char* boundary_type_name(BoundaryType t);

struct BoundarySpec {
  std::string body;
  std::string group;                       // physical surface or volume group name, or empty when a box is given
  std::optional<std::array<Vec3, 2>> box;  // [min, max] in placed coordinates
  BoundaryType type = BoundaryType::fixed;
  Vec3 velocity{0, 0, 0};
  std::array<bool, 3> components{true, true, true};
  Vec3 displacement{0, 0, 0};  // type = "displacement": u(t) = displacement x curve(t) (x 1 without a curve)
  std::string curve;           // [curves] name scaling the velocity or the displacement; empty: constant
  std::string name;            // for the reaction columns; default "boundary<k>"
  Vec3 moment_about{0, 0, 0};  // point the reaction moment is taken about (placed coordinates)
};

// [[load]]: a follower pressure on a physical surface group (normal to the current surface, on
// the current area), positive pushing into the body, scaled by a curve.
enum class LoadType { pressure };

struct LoadSpec {
  std::string body, group;
  double pressure = 0;  // Pa
  std::string curve;    // empty: constant
  LoadType type = LoadType::pressure;
};

// node_to_surface: each slave node on its closest master point; mortar: segment-to-segment
// integrals of the slave surface; automatic: contact_method() chooses.
enum class ContactMethod { automatic, node_to_surface, mortar };
const char* contact_method_name(ContactMethod m);

// [[contact]]: slave nodes of one body's surface against another body's surface or a rigid plane.
struct ContactSpec {
  std::string slave_body, slave_surface, master_body, master_surface;
  std::optional<std::array<Vec3, 2>> plane;  // point, outward normal (rigid plane master)
  double friction = 0;                       // Coulomb coefficient mu
  bool two_pass = false;                     // also the master's nodes against the slave surface
  // Mortar only: also the master's convex edge and corner nodes (faces meeting at more than
  // kEdgePassAngleDeg) against the slave surface, node to surface (surfaces.cpp).
  bool edge_pass = true;
  ContactMethod method = ContactMethod::automatic;
};

// The method of a [[contact]] entry: its own, or by default mortar (segment-to-segment integrals of
// the slave surface: a pressure field that passes the contact patch test) for a deformable master
// of another surface in one pass, and node_to_surface for self-contact, a rigid plane and two_pass
// (mortar has no second pass: its rows already weigh the master's nodes).
ContactMethod contact_method(const ContactSpec& c);
// A [[contact]] entry whose master is its own slave surface (skin on skin).
bool is_self_contact(const ContactSpec& c);

// [contact_solver]: the Uzawa iterations and the search.
struct ContactSettings {
  double tolerance = 1e-6;  // stop when max |dr| <= tolerance * max |r| over the contact nodes
  int max_iterations = 200;
  double search_factor = 0.5;  // search distance and penetration band, in mean master edges
  // Verlet skin of the node-to-surface search, in mean master edges: candidate triangles are
  // gathered within band + skin and kept until a node has moved half the skin (0: every step).
  double verlet_skin = 0.5;
  // The reported contact pressure is the per-step pressure r_n / A averaged over an exponential
  // window of tau = max(pressure_window, 10 x the initial critical step), s.
  double pressure_window = 1e-5;
  // The area of the pressure "sensor": at each output the reported pressure field is also averaged
  // over every disc of this area on the slave surfaces (centred on a contact node), and the largest
  // such average is reported. Unlike a node's value it does not grow when the mesh is refined at
  // an edge or corner load, m^2.
  double pressure_average_area = 25e-6;
  // A row found deeper inside its master than this speed times the step (a penetration the last
  // step did not make: a node that slid back over a master's edge, a row that just appeared) is
  // pushed out at this speed instead of in one step, m/s.
  double recovery_speed = 1.0;
  // The Uzawa sweep in slabs: the rows are cut into at most this many slabs along the contact's
  // longest extent, the even slabs swept in parallel (each in row order, Gauss-Seidel), then the
  // odd ones, then the rows shared between slabs of one parity in order (contact/bipotential.cpp).
  // The slabs do not depend on the thread count (the same bits on any number of threads); 1: one
  // sweep in row order. At most one slab per kMinRowsPerSweepBlock rows: a slab's sweep (~0.1 us
  // a row) must outweigh the fork and join of the threads around it (a few us).
  int sweep_blocks = 16;
  static constexpr std::size_t kMinRowsPerSweepBlock = 256;
};

// [[pipeline.meshes]]: how tactus-pipeline makes a mesh (or fibre file) the scenario uses.
enum class MeshKind { labels, box, stl, fibres };
const char* mesh_kind_name(MeshKind k);
struct MeshPlanEntry {
  std::string output;  // relative to the pipeline's work folder
  MeshKind kind = MeshKind::labels;
  std::string args;  // tactus-mesh options
  std::string file;  // kind = stl: the STL (relative to the scenario); kind = fibres: the mesh (relative to the work folder)
};

struct Scenario {
  std::filesystem::path file;
  RunSpec run;
  DampingSpec damping;
  std::vector<BodySpec> bodies;
  std::map<std::string, MaterialInstance> materials;
  // The laws the reader made from `materials` (by name; a scenario built in code has none, and
  // build_model makes them from the values).
  std::map<std::string, Material> laws;
  std::vector<BoundarySpec> boundaries;
  std::vector<LoadSpec> loads;
  std::map<std::string, CurveSpec> curves;
  std::vector<ContactSpec> contacts;
  ContactSettings contact_solver;
  std::vector<MeshPlanEntry> mesh_plan;  // [[pipeline.meshes]]
};

// Relative mesh and fibre paths are resolved against `mesh_dir` when given (tactus-solve --meshes,
// used by the pipeline), else against the scenario file's folder.
Scenario read_scenario(const std::filesystem::path& file, const std::filesystem::path& mesh_dir = {});

// The mesh plan as tactus-pipeline reads it: {"meshes": [{output, kind, args, file}], "inputs":
// [every mesh and fibre file the bodies read, resolved]}.
std::string mesh_plan_json(const Scenario& sc);

// The declarations, in reference order (sections, then one per material type).
std::vector<SectionSpec> scenario_reference();
// Markdown reference of every key (docs/scenario-reference.md).
std::string scenario_reference_markdown();

}  // namespace tactus::solver
