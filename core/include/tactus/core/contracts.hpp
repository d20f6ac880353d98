#pragma once
// The file contracts between the stages, declared once: label ids, mesh group names and tags,
// result field names, history.csv columns and run.json keys. Writers and readers (the solver,
// postproc, the mesher, segment) use these names; `tactus-solve results-reference` prints them as
// docs/results-reference.md and .json (the Python pipeline and test scripts read the JSON), and a
// test keeps both files equal to these declarations.
#include <array>

namespace tactus::contracts {

// --- labels.h5 -------------------------------------------------------------------------------
inline constexpr int kBackgroundLabel = 0;
inline constexpr int kSoftTissueLabel = 1;
inline constexpr int kFirstBoneLabel = 2;  // 2.. one id per bone
inline constexpr const char* kSoftTissueName = "soft_tissue";
inline constexpr const char* kLabelsDataset = "/labels";

// --- meshes ------------------------------------------------------------------------------------
// Surfaces of the mesher's anatomy meshes, and of gmsh objects.
inline constexpr int kSkinTag = 1001, kBoneInterfaceTag = 1002, kObjectSurfaceTag = 20;
inline constexpr const char* kSkinGroup = "skin";
inline constexpr const char* kBoneInterfaceGroup = "bone_interface";
inline constexpr const char* kObjectSurfaceGroup = "surface";

// --- results: state .vtu fields ----------------------------------------------------------------
struct FieldSpec {
  const char* name;
  int components;
  const char* unit;
  const char* doc;
};

namespace point {
inline constexpr FieldSpec displacement{"displacement", 3, "m", "u = x - X"};
inline constexpr FieldSpec velocity{"velocity", 3, "m/s", "v at the state's time"};
inline constexpr FieldSpec contact_pressure{"contact_pressure", 1, "Pa", "normal reaction over the node's tributary area (slave nodes)"};
inline constexpr FieldSpec contact_traction{"contact_traction", 3, "Pa", "tangential (friction) reaction over the tributary area"};
inline constexpr FieldSpec contact_status{"contact_status", 1, "", "-1 far from any master, 0 open, 1 stick, 2 slip"};
inline constexpr FieldSpec contact_gap{"contact_gap", 1, "m", "gap h to the master (NaN when far)"};
inline constexpr FieldSpec contact_area{"contact_area", 1, "m^2",
                                        "tributary area A of the node's contact row (mortar: its share of the overlap), so that pressure x area "
                                        "is its normal reaction; 0 without a row"};
inline constexpr FieldSpec node_id{"node_id", 1, "",
                                   "the node's number in every message, summary and quality.json (1-based; for a one-body mesh its .msh "
                                   "tag; bodies follow each other in scenario order)"};
inline constexpr FieldSpec grip_region{"grip_region", 1, "",
                                       "a grasp's hand region of the node, an index into field data grip_region_names (-1: none); "
                                       "written only for a run with [grasp]"};
inline constexpr std::array<const FieldSpec*, 9> all{&node_id,        &displacement, &velocity,     &contact_pressure, &contact_traction,
                                                     &contact_status, &contact_gap,  &contact_area, &grip_region};
}  // namespace point

namespace cell {
inline constexpr FieldSpec group{"group", 1, "", "physical volume tag in the body's own mesh file"};
inline constexpr FieldSpec cauchy_stress{"cauchy_stress", 6, "Pa", "Cauchy stress (xx, yy, zz, xy, yz, xz)"};
inline constexpr FieldSpec von_mises{"von_mises", 1, "Pa", "von Mises stress of the Cauchy stress"};
inline constexpr FieldSpec material{"material", 1, "", "index into run.json materials"};
inline constexpr FieldSpec body{"body", 1, "", "index into run.json bodies"};
inline constexpr FieldSpec jacobian{"J", 1, "", "volume ratio det F"};
inline constexpr FieldSpec tet_id{"tet_id", 1, "", "the tet's number in every message, summary and quality.json (1-based, as node_id)"};
inline constexpr std::array<const FieldSpec*, 7> all{&tet_id, &group, &cauchy_stress, &von_mises, &material, &body, &jacobian};
}  // namespace cell

// Field data of every state: "TimeValue" (s, as ParaView reads it), "units", "points" (which
// configuration the points are), and the names behind the indices: "body_names", "material_names".
inline constexpr const char* kPointsNote = "points";
inline constexpr const char* kBodyNames = "body_names";
inline constexpr const char* kMaterialNames = "material_names";
inline constexpr const char* kGripRegionNames = "grip_region_names";  // a grasp's state: the names behind grip_region

// --- results: history.csv ----------------------------------------------------------------------
struct ColumnSpec {
  const char* name;
  const char* unit;
  const char* doc;
};

namespace history {
inline constexpr ColumnSpec step{"step", "", "step index n"};
inline constexpr ColumnSpec time{"time", "s", "t^n"};
inline constexpr ColumnSpec dt{"dt", "s", "the step that reached t^n"};
inline constexpr ColumnSpec kinetic_energy{"kinetic_energy", "J", "kinetic energy at t^n"};
inline constexpr ColumnSpec internal_energy{"internal_energy", "J", "strain energy at t^n"};
inline constexpr ColumnSpec damping_work{"damping_work", "J", "work of the Rayleigh damping forces so far"};
inline constexpr ColumnSpec external_work{"external_work", "J", "work of gravity and of the supports (prescribed dofs) so far"};
inline constexpr ColumnSpec contact_work_normal{"contact_work_normal", "J", "energy taken out by the normal contact reactions"};
inline constexpr ColumnSpec contact_work_friction{"contact_work_friction", "J", "energy dissipated by friction"};
inline constexpr ColumnSpec energy_balance_error{"energy_balance_error", "J",
                                                 "kinetic + internal + damping + contact work - external work - initial energy"};
inline constexpr ColumnSpec critical_step{"critical_step", "s",
                                          "the stable limit at t^n: the larger of the element estimate min L_e / c_e and the nodal bound "
                                          "(docs/design.md section 5)"};
inline constexpr ColumnSpec contact_force{"contact_force", "N", "|sum of the contact reactions on the slave nodes|"};
inline constexpr ColumnSpec contact_force_x{"contact_force_x", "N", "its x component"};
inline constexpr ColumnSpec contact_force_y{"contact_force_y", "N", "its y component"};
inline constexpr ColumnSpec contact_force_z{"contact_force_z", "N", "its z component"};
inline constexpr ColumnSpec contact_normal_force{"contact_normal_force", "N", "sum of the normal reactions"};
inline constexpr ColumnSpec contact_area{"contact_area", "m^2", "tributary area of the nodes pressed"};
inline constexpr ColumnSpec peak_pressure{"peak_pressure", "Pa",
                                          "largest nodal contact pressure, averaged over the pressure window (contact_solver.pressure_window)"};
inline constexpr ColumnSpec peak_pressure_x{"peak_pressure_x", "m", "where: x"};
inline constexpr ColumnSpec peak_pressure_y{"peak_pressure_y", "m", "where: y"};
inline constexpr ColumnSpec peak_pressure_z{"peak_pressure_z", "m", "where: z"};
inline constexpr ColumnSpec peak_step_pressure{"peak_step_pressure", "Pa",
                                               "largest r_n / A of this step alone: first-touch impulses over one step, growing like 1/dt"};
inline constexpr ColumnSpec contact_nodes{"contact_nodes", "", "slave nodes pressed"};
inline constexpr ColumnSpec stick_nodes{"stick_nodes", "", "of which sticking"};
inline constexpr ColumnSpec slip_nodes{"slip_nodes", "", "of which slipping"};
inline constexpr ColumnSpec uzawa_iterations{"uzawa_iterations", "", "Uzawa sweeps this step"};
inline constexpr std::array<const ColumnSpec*, 26> all{&step,
                                                       &time,
                                                       &dt,
                                                       &kinetic_energy,
                                                       &internal_energy,
                                                       &damping_work,
                                                       &external_work,
                                                       &contact_work_normal,
                                                       &contact_work_friction,
                                                       &energy_balance_error,
                                                       &critical_step,
                                                       &contact_force,
                                                       &contact_force_x,
                                                       &contact_force_y,
                                                       &contact_force_z,
                                                       &contact_normal_force,
                                                       &contact_area,
                                                       &peak_pressure,
                                                       &peak_pressure_x,
                                                       &peak_pressure_y,
                                                       &peak_pressure_z,
                                                       &peak_step_pressure,
                                                       &contact_nodes,
                                                       &stick_nodes,
                                                       &slip_nodes,
                                                       &uzawa_iterations};
// After those, per [[boundary]] entry in scenario order, named by its `name` (<name> below):
// x, y, z of each (history_column_prefix + name + "_x").
struct ColumnFamily {
  const char* prefix;
  const char* unit;
  const char* doc;
};
inline constexpr ColumnFamily reaction{"reaction_", "N", "force the support applies to the body (x, y, z columns)"};
inline constexpr ColumnFamily moment{"moment_", "N m", "moment of that force about the boundary's moment_about (x, y, z columns)"};
inline constexpr std::array<const ColumnFamily*, 2> per_boundary{&reaction, &moment};
// Then, only with mass scaling on (run.minimum_time_step > 0), one column per body: prefix + body name.
inline constexpr ColumnFamily added_mass{"added_mass_", "kg", "mass added to the body by mass scaling so far (one column per body)"};
// Then per rigid body (material type rigid; <name>: body, material and piece, e.g. hand_bone_3),
// x, y, z of each: prefix + name + "_x".
inline constexpr ColumnFamily rigid_centre{"rigid_centre_", "m", "its centre of mass"};
inline constexpr ColumnFamily rigid_rotation{"rigid_rotation_", "rad",
                                             "its rotation from the reference placement, as a rotation vector (axis times angle)"};
inline constexpr ColumnFamily rigid_velocity{"rigid_velocity_", "m/s", "velocity of its centre (at the half step before the row's time)"};
inline constexpr ColumnFamily rigid_angular_velocity{"rigid_angular_velocity_", "rad/s", "its angular velocity (likewise)"};
inline constexpr ColumnFamily rigid_reaction{
    "rigid_reaction_", "N",
    "force its support applies when its motion is prescribed (bodies.rigid_velocity; contact excluded: see the contact columns), else 0"};
inline constexpr ColumnFamily rigid_moment{"rigid_moment_", "N m", "moment of that support about its centre"};
inline constexpr std::array<const ColumnFamily*, 6> per_rigid_body{&rigid_centre,           &rigid_velocity, &rigid_rotation,
                                                                   &rigid_angular_velocity, &rigid_reaction, &rigid_moment};
// Then, with a [skeleton], one column per joint (<name>: the skeleton's joint name).
inline constexpr ColumnFamily joint_flexion{"flexion_", "deg", "the joint's flexion from the mesh's posture"};
// Then, with a [grasp]:
inline constexpr ColumnSpec grip_force{"grip_force", "N", "normal contact force between the handle and the other bodies (the last contact step)"};
inline constexpr ColumnSpec grip_target{"grip_target", "N", "the grip force the controller is steering to (ramped)"};
inline constexpr ColumnSpec grip_drive{"grip_drive", "N m", "the PI loop's drive s: each torque-driven joint gets s x its weight"};
inline constexpr std::array<const ColumnSpec*, 3> grasp{&grip_force, &grip_target, &grip_drive};
// Then per grip region (<name>: a phalanx as the skeleton names it, or palm_thenar, palm_central,
// palm_hypothenar; docs/design.md, "Joints and the grasp"), the handle's rows only:
inline constexpr ColumnFamily region_force{"region_force_", "N", "normal contact force the handle puts on the region's skin"};
inline constexpr ColumnFamily region_area{"region_area_", "m^2", "tributary area of the region's skin nodes the handle presses"};
inline constexpr ColumnFamily region_peak_pressure{"region_peak_pressure_", "Pa", "largest nodal pressure of the handle on the region"};
inline constexpr std::array<const ColumnFamily*, 3> per_grip_region{&region_force, &region_area, &region_peak_pressure};
// Then per digit (thumb, index, middle, ring, little) and the palm: the sum of its regions' force.
inline constexpr ColumnFamily digit_force{"digit_force_", "N", "normal contact force the handle puts on the digit (all its phalanges) or the palm"};
}  // namespace history

// --- results: run.json (the keys readers use) ---------------------------------------------------
namespace run_json {
inline constexpr const char* status = "status";                          // "completed" | "failed"
inline constexpr const char* message = "message";                        // why it failed, or null
inline constexpr const char* materials = "materials";                    // names behind the cell field "material"
inline constexpr const char* bodies = "bodies";                          // names behind the cell field "body"
inline constexpr const char* formulations = "formulations";              // {material name: "standard" | "anp"}
inline constexpr const char* pressure_smoothing = "pressure_smoothing";  // {ANP material name: smoothing passes}
inline constexpr const char* volume_floor = "volume_floor";              // {ANP material name: J below which its barrier acts}
inline constexpr const char* steps = "steps";
inline constexpr const char* nodes = "nodes";
inline constexpr const char* tets = "tets";
inline constexpr const char* end_time = "end_time";  // s, exactly the end time reached
inline constexpr const char* output_times = "output_times";
inline constexpr const char* outputs = "outputs";
inline constexpr const char* wall_time = "wall_time_s";
inline constexpr const char* time_step = "time_step";  // {min, max, safety, min_ratio_to_nominal, critical_initial, ...}
inline constexpr const char* timing = "timing_s";      // {stress_passes, contact, rest}
inline constexpr const char* energy = "energy";        // {initial, kinetic, internal, ..., balance_error}
inline constexpr const char* peak_von_mises = "peak_von_mises_at_outputs";
// {pairs: [{name, friction, slave_nodes, master, peak_force, peak_area, peak_pressure}] (one per directed pair;
// the totals count each two_pass entry once), steps_in_contact, peak_force, peak_area, peak_pressure (windowed),
// peak_step_pressure (one step's r_n / A), pressure_window (s), pressure_average_area (m^2), at_outputs: [{time,
// normal_force, area, peak_pressure, averaged_peak_pressure (the largest average of the pressure field over a disc
// of pressure_average_area), averaged_at}], search: {verlet_skin, searches (pair-steps of the search),
// list_builds (of them, how many rebuilt the Verlet lists or integrated the mortar segments)}, uzawa}
inline constexpr const char* contact = "contact";
inline constexpr const char* reactions = "reactions";  // [{name, moment_about, final_force, final_moment, peak_force: {value, time, vector}}]
// Only with mass scaling on: {minimum_time_step, added_mass_limit, bodies: {name: {mass, added_mass, fraction}},
// added_kinetic_energy, added_momentum}
inline constexpr const char* mass_scaling = "mass_scaling";
// Only under mpirun: per rank {rank, tets, halo_doubles_per_pass, halo_messages_per_pass, owned_nodes (those its
// atoms own; with owned-node stepping it sends every rank the forces of those that every rank integrates, else of all),
// stress_passes_s, contact_s, wall_time_s, model_bytes and solver_bytes (as memory_bytes), sums_s (of stress_passes_s: the pass's one
// gather of sums, minima and forces, with its wait for the slowest rank), force_gather_s (of sums_s: packing and unpacking
// the forces), peak_resident_bytes (the
// rank's process, Linux VmHWM), anp_exchange_doubles_per_pass and anp_exchange_messages_per_pass (the ANP J pass's
// exchanges of volumes and ghost nodes' values; 0 without ANP blocks), integrated_nodes (the nodes it integrates: its
// own and those every rank integrates; 0 on one rank, meaning every node), ghost_doubles_per_exchange
// (what it sends after each update of u or v to the ranks that read its nodes; 0 on one rank), resident_bytes_at_end
// (VmRSS when the report is made, against the peak: what the run holds, not what reading the meshes took),
// gather_doubles_per_pass (what it sends in the pass's one gather: its exact sums' 142 words, its minima, and the
// forces of its owned nodes that every rank integrates)}
inline constexpr const char* ranks = "ranks";
// {model, solver}: bytes of this process's data structures: the model (Model::memory_bytes: every body's nodes and
// tets, the input mesh's copy) and the integrator with its stress pass (ExplicitSolver::memory_bytes), the figures
// the per-rank memory bound is checked on (the same in each "ranks" entry as model_bytes and solver_bytes)
inline constexpr const char* memory = "memory_bytes";
inline constexpr std::array<const char*, 20> all{
    status,   message,      materials, formulations, pressure_smoothing, volume_floor, bodies, steps,          nodes,   tets,
    end_time, output_times, outputs,   wall_time,    time_step,          timing,       energy, peak_von_mises, contact, reactions};
}  // namespace run_json

}  // namespace tactus::contracts
