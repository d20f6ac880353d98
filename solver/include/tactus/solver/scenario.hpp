#pragma once
// scenario.toml: what to simulate. Every key is declared (parameters.hpp) with unit and range;
// unknown keys, missing required keys and out-of-range values are errors naming the key. The
// parameter structs the physics takes live with the physics (run_settings.hpp, curve.hpp,
// contact_settings.hpp, material.hpp); this header includes them, never the reverse
// (scripts/include_direction.py checks it).
// Lengths m, times s, velocities m/s, stresses Pa, densities kg/m^3.
#include <array>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "tactus/core/vec3.hpp"
#include "tactus/solver/contact_settings.hpp"
#include "tactus/solver/curve.hpp"
#include "tactus/solver/joint_settings.hpp"
#include "tactus/solver/material.hpp"
#include "tactus/solver/parameters.hpp"
#include "tactus/solver/run_settings.hpp"

namespace tactus::solver {

struct MaterialInstance {
  std::string name, type;
  MaterialValues values;  // validated against the law's declarations
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
  std::optional<Vec3> rigid_guide;  // its free rigid pieces translate along this direction only
  std::filesystem::path fibres;     // optional .vtu with per-tet cell data fibre_1, fibre_2
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

// [[pipeline.meshes]]: how tactus-pipeline makes a mesh (or fibre file) the scenario uses.
enum class MeshKind { labels, box, stl, fibres, skeleton, cylinder };
const char* mesh_kind_name(MeshKind k);
struct MeshPlanEntry {
  std::string output;  // relative to the pipeline's work folder
  MeshKind kind = MeshKind::labels;
  std::string args;  // tactus-mesh options
  std::string file;  // kind = stl: the STL (relative to the scenario); fibres, skeleton: the mesh (relative to the work folder)
  // kind = cylinder (tactus-mesh cylinder): keys of their own so that a design study can vary them.
  std::optional<double> radius, length, sleeve;  // m
};

// [skeleton]: the bones of one body and the joints between them (tactus-mesh skeleton, or the
// phantom's joints.json), for [[joint]] and [grasp] to move.
struct SkeletonSpec {
  std::string body;
  std::filesystem::path file;  // skeleton.json (relative to the scenario file, or to --meshes)
};

struct Scenario {
  std::filesystem::path file;
  std::vector<std::string> overrides;  // tactus-solve --set KEY=VALUE, applied over the file, in order
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
  std::optional<SkeletonSpec> skeleton;
  std::vector<JointSpec> joints;  // [[joint]]
  GraspSpec grasp;                // [grasp] (off: no handle)
};

// Relative mesh and fibre paths are resolved against `mesh_dir` when given (tactus-solve --meshes,
// used by the pipeline), else against the scenario file's folder.
// `overrides` ("KEY=VALUE", tactus-solve --set) replace values of the file before it is read:
// KEY is a dotted path (`grasp.target_force`, `materials.sleeve.mu`, `pipeline.meshes.2.radius`,
// an entry of a [[...]] list by its 0-based index), VALUE a TOML value (a bare word is a string).
Scenario read_scenario(const std::filesystem::path& file, const std::filesystem::path& mesh_dir = {}, const std::vector<std::string>& overrides = {});

// The mesh plan as tactus-pipeline reads it: {"meshes": [{output, kind, args, file}], "inputs":
// [every mesh and fibre file the bodies read, resolved]}.
std::string mesh_plan_json(const Scenario& sc);

// The declarations, in reference order (sections, then one per material type).
std::vector<SectionSpec> scenario_reference();
// Markdown reference of every key (docs/scenario-reference.md).
std::string scenario_reference_markdown();

}  // namespace tactus::solver
