#pragma once
// The assembled discrete model: every body's nodes and tets in one numbering, reordered for
// memory locality, in flat structure-of-arrays form. Built once from a Scenario; the time
// integrator only reads it.
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "tactus/core/mesh.hpp"
#include "tactus/solver/contact.hpp"
#include "tactus/solver/curve.hpp"
#include "tactus/solver/joint_settings.hpp"
#include "tactus/solver/loading.hpp"
#include "tactus/solver/material.hpp"

namespace tactus::solver {

// The atom: a run of kAtomTets consecutive tets of one material block (a block's last may be
// shorter), the unit every nodal sum is taken in. The stress pass scatters each atom's forces into
// its own array and sums them per node in atom order; the decomposition gives ranks whole atoms.
// Atoms do not depend on the thread or rank count, so neither do the sums (OpenRadioss' /PARITH/ON).
inline constexpr std::size_t kAtomTets = 128;

// Tets of one material, contiguous in element order: the force kernel dispatches on the
// material once per block, never per element. The law's per-element data (hgo: fibre directions)
// belongs to the block: its own array when the elements bring their own (a body's fibres file),
// else the material's constants for every element (stride 0).
struct MaterialBlock {
  std::string name;  // material name in the scenario
  Material material;
  std::size_t begin = 0, end = 0;    // element range
  std::vector<double> element_data;  // material.type().element_data_size per element, or empty
  // The joint gaps of a skeleton's body: its deformable tets whose four nodes all lie on its bones
  // (rigid pieces), or three of them on two different bones. The joints place those nodes: a tet
  // with four has no degree of freedom of its own, and one with three has a face that spans the
  // joint, which flexing squeezes flat whatever the fourth node does. Flexing a joint about its
  // centre crushes such a tet whatever its material (the cartilage and capsule it stands for
  // slide and fold), so it carries no stress and sets no step. Named "<material>_joint_gap".
  bool joint_gap = false;

  // Released (Model::release_tet_geometry): the per-element data lives with the stress pass of
  // the rank that runs each tet; reading it here is a programming error.
  bool element_data_released = false;

  bool has_stress_pass() const { return !joint_gap && !material.rigid(); }
  bool per_element_data() const { return !element_data.empty() || element_data_released; }
  const double* data() const {
    if (element_data_released) throw std::logic_error("material block '" + name + "': its per-tet data was released (Model::release_tet_geometry)");
    return per_element_data() ? element_data.data() : material.constant_element_data().data();
  }
  std::size_t data_stride() const { return per_element_data() ? material.type().element_data_size : 0; }
  const double* data_of(std::size_t e) const { return data() + data_stride() * (e - begin); }
};

// A body: its ranges in the input numbering of Model::input_mesh, whose tet_group and
// triangle_group hold the tags of the body's own mesh file (two bodies may use the same tags).
struct BodyRange {
  std::string name;
  std::size_t node_begin = 0, node_end = 0;
  std::size_t tet_begin = 0, tet_end = 0;
  std::size_t triangle_begin = 0, triangle_end = 0;
  std::size_t group_begin = 0, group_end = 0;  // its physical groups in input_mesh.groups
  // Its rigid pieces (rigid.hpp): a prescribed velocity and angular velocity (about each piece's
  // centre), scaled by curves[rigid_curve] (-1: constant).
  Vec3 initial_angular_velocity{0, 0, 0};  // about the body's centre of mass (model.initial_velocity holds the field)
  bool rigid_prescribed = false;
  Vec3 rigid_velocity{0, 0, 0}, rigid_angular_velocity{0, 0, 0};
  std::int32_t rigid_curve = -1;
  Vec3 rigid_guide{0, 0, 0};    // a unit direction: its free pieces translate along it only (0: free)
  Vec3 against_shift{0, 0, 0};  // what `against` moved it by after scale, rotate and translate
};

struct Model {
  std::string source = "scenario";  // the scenario file it was built from, for messages
  // Nodes (internal, locality-ordered numbering), 3 doubles per node.
  std::size_t num_nodes = 0;
  std::vector<double> X;     // reference positions
  std::vector<double> mass;  // lumped (row-sum) mass: rho V / 4 from each adjacent tet
  std::vector<double> initial_velocity;

  // Elements (sorted by block, then along a space-filling curve).
  std::size_t num_elements = 0;
  std::vector<std::int32_t> conn;  // 4 per tet
  std::vector<double> grad;        // 9 per tet: grad N_1, grad N_2, grad N_3 (grad N_0 = -sum)
  std::vector<double> volume;      // reference volume
  std::vector<MaterialBlock> blocks;

  // Constraints: per dof (3 per node), 0 free, 1 prescribed velocity (0 = fixed), 2 prescribed
  // displacement; the velocity or the displacement in constraint_velocity, scaled by
  // curves[constraint_curve] (-1: constant); constraint_boundary: the [[boundary]] entry whose
  // reaction the dof's support force counts in (the last one that selects it; -1 none).
  std::vector<std::uint8_t> constrained;
  std::vector<double> constraint_velocity;
  std::vector<std::int32_t> constraint_curve, constraint_boundary;
  std::vector<CurveSpec> curves;
  // curves[curve] at time t; 1 for curve -1 (none: constant).
  double curve_at(std::int32_t curve, double t) const { return curve < 0 ? 1.0 : curves[static_cast<std::size_t>(curve)].at(t); }
  std::vector<BoundaryReactionSpec> boundaries;  // one per [[boundary]] entry
  std::vector<PressureLoad> pressure_loads;
  std::int32_t gravity_curve = -1;

  // Mapping back to the input numbering, for output and messages.
  std::vector<std::int32_t> node_of_input;  // internal index of input node i
  std::vector<std::int32_t> input_element;  // input index of internal tet
  // All bodies, input numbering, file tags; its tets and nodes are dropped once the model is built
  // (each held twice, 16 bytes per tet and 24 per node): internal tet e is input tet
  // input_element[e], its nodes conn's through node_of_input, and input node i is at X's
  // node_of_input[i]. tet_group keeps one tag per tet.
  TetMesh input_mesh;
  std::vector<BodyRange> bodies;  // each body's input tets are one range (body_of_tet)

  // Contact (internal numbering): directed slave -> master pairs and the iteration settings.
  std::vector<ContactPair> contact_pairs;
  ContactSettings contact_settings;

  // The bones' motion by their joints (joint_settings.hpp); off without a [skeleton].
  JointDriveSetup joint_drive;

  // On ranks, once the rank's stress pass holds its own tets' geometry and connectivity
  // (InternalForces::hold_own_geometry) and the restart check has run: frees every tet's nodes,
  // reference gradients, volumes and per-tet law data (96 bytes per tet and the law's), which
  // every rank builds with the model. A later reader fails loudly (tet_geometry_released, conn
  // empty) rather than reading nothing. A step towards the model's scatter (docs/design.md).
  void release_tet_geometry();
  bool tet_geometry_released = false;

  std::size_t memory_bytes() const;                          // everything held, including the input mesh copy
  std::string describe_element(std::size_t internal) const;  // "tet 123 (body hand, group bone, material bone)"
  const MaterialBlock& block_of(std::size_t internal) const;
  // Input-numbering index of an internal node (a search: for messages and reports, not loops).
  std::size_t input_node(std::size_t internal) const;
  // The physical groups of body b, in file order; one of them by dimension and name (or nullptr).
  std::vector<const PhysicalGroup*> body_groups(std::size_t body) const;
  const PhysicalGroup* body_group(std::size_t body, int dim, const std::string& name) const;
  // The body an input node, or an input tet, belongs to (a search over the bodies' ranges).
  std::size_t body_of_node(std::size_t input_node) const;
  std::size_t body_of_tet(std::size_t input_tet) const;
};

// A model from an in-memory mesh (tests and benchmarks; a scenario's: build_model in model_build.hpp): one body, one material for every group.
Model build_model(const TetMesh& mesh, const Material& material, const std::string& material_name = "material",
                  const Vec3& initial_velocity = {0, 0, 0}, bool reorder = true);

// Reorders nodes and elements along a Morton (Z-order) curve so that neighbouring tets share
// cache lines; exposed for the benchmarks.
void reorder_for_locality(Model& model);

// Constrains the chosen components of every node whose reference position satisfies `select`
// to the given velocity (0 = fixed). Returns how many nodes were selected. For tests/benchmarks.
std::size_t constrain_nodes(Model& model, const std::function<bool(const double* X)>& select, std::array<bool, 3> components,
                            const Vec3& velocity = {0, 0, 0});
}  // namespace tactus::solver
