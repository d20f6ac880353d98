#pragma once
// What a run writes (solver/include/tactus/solver/run.hpp lists the files): the state .vtu files
// and their results.pvd listing, history.csv from one table of columns, and run.json. Names come
// from the file contracts (core/contracts.hpp).
#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "tactus/core/file_io.hpp"
#include "tactus/solver/contact.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/grip_regions.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/rigid.hpp"
#include "tactus/solver/scenario.hpp"

namespace tactus::solver {

// The state at one time as a .vtu (input numbering). Returns each block's largest von Mises.
// cell_records: hands every tet's cell record at u to its sink (ExplicitSolver::cell_records:
// the stress pass's own evaluation, on ranks gathered to this process).
using CellRecords = std::function<void(const CellSink& sink)>;
std::vector<double> write_state(const Model& m, const std::filesystem::path& file, const std::vector<double>& u, const std::vector<double>& v,
                                const CellRecords& cell_records, const ContactSolver* contact,
                                double time,                            // time (s): field data TimeValue
                                const GripRegions* regions = nullptr);  // a grasp: each node's region (grip_region)
void write_pvd(const std::filesystem::path& file, const std::vector<std::pair<double, std::string>>& entries);

// One history row's inputs.
struct HistoryRow {
  std::size_t step = 0;
  double time = 0, dt = 0, critical_step = 0;
  const Energies* energy = nullptr;
  const ContactStepReport* contact = nullptr;
  Vec3 peak_at{0, 0, 0};
  const Reactions* reactions = nullptr;             // one force and moment per boundary (model.boundaries)
  const std::vector<double>* added_mass = nullptr;  // mass scaling: kg per body (model.bodies), or none
  const std::vector<RigidBody>* rigid = nullptr;    // the rigid bodies (rigid.hpp), or none
  const JointDrive* joints = nullptr;               // the joint drive (joint_drive.hpp), or none
  const GripRegions* regions = nullptr;             // the grasp's regions, summed for this row (grip_regions.hpp), or none
};

// A rigid body's name as it appears in column names: "hand/bone #3" -> "hand_bone_3".
std::string rigid_column_name(const std::string& name);

// history.csv: its header and rows both come from the one column table (history.cpp).
class HistoryWriter {
 public:
  // `boundaries`: the model's, for the reaction columns after the fixed ones; `mass_scaled_bodies`:
  // with mass scaling on, the bodies' names, for an added_mass_<body> column each after those.
  // `resume_at`: continue a history written up to that many bytes (a restart): the file is cut
  // there and appended to; InputError when it is shorter.
  static constexpr std::uintmax_t kNew = static_cast<std::uintmax_t>(-1);
  HistoryWriter(const std::filesystem::path& file, const std::vector<BoundaryReactionSpec>& boundaries,
                const std::vector<std::string>& mass_scaled_bodies = {}, std::uintmax_t resume_at = kNew,
                const std::vector<std::string>& rigid_bodies = {}, const JointDrive* joints = nullptr, const GripRegions* regions = nullptr);
  void write(const HistoryRow& row);
  // Hands every row written so far to the file system and returns the file's length (a checkpoint's row).
  std::uintmax_t flush();
  void close();

 private:
  std::unique_ptr<FileWriter> out_;  // every write checked: a full disk stops the run, never cuts the history short
  std::filesystem::path file_;
  std::size_t boundaries_ = 0, mass_scaled_bodies_ = 0, rigid_bodies_ = 0, joints_ = 0;
  bool grasp_ = false;
  std::size_t regions_ = 0, digits_ = 0;
  std::string line_;  // the row being written (its capacity kept: no allocation per step)
};

// The peaks over a run that run.json reports (contact over every step, von Mises at the outputs).
struct RunPeaks {
  double force = 0, force_time = 0, area = 0, area_time = 0, pressure = 0, pressure_time = 0;
  double step_pressure = 0, step_pressure_time = 0;  // r_n / A of one step (impulses)
  Vec3 pressure_at{0, 0, 0};
  std::size_t pressure_node = 0;
  int max_iterations = 0;
  std::size_t unconverged_steps = 0, contact_steps = 0;
  std::size_t recovering_rows = 0;  // contact rows pushed out at contact_solver.recovery_speed, summed over the steps
  // Contact rows swept, and of them those swept in order (between the blocks, or all of a step not cut), summed over the steps.
  std::size_t rows_swept = 0, rows_in_order = 0;
  std::vector<double> von_mises;  // per block
  // Per boundary: the largest |reaction force|, when, and the force then.
  std::vector<double> reaction_peak, reaction_peak_time, reaction_peak_force;  // 1, 1, 3 per boundary
  // Per directed contact pair: the largest |force| on its slave nodes, area and pressure, and when.
  struct PairPeaks {
    double force = 0, force_time = 0, normal_force = 0, area = 0, area_time = 0, pressure = 0, pressure_time = 0;
  };
  std::vector<PairPeaks> pairs;
  // At each output: the contact force and area (the step's, and averaged over the pressure's
  // window), the largest nodal pressure and the largest average over the sensor area
  // (ContactSolver::averaged_peak_pressure) with its centre.
  struct AtOutput {
    double time = 0, normal_force = 0, area = 0, peak_pressure = 0, averaged_peak_pressure = 0;
    Vec3 averaged_at{0, 0, 0};
    double windowed_normal_force = 0, windowed_area = 0;
  };
  std::vector<AtOutput> at_outputs;
  void add_contact_step(const ContactStepReport& c, double t, const Vec3& peak_at, const std::vector<PairStepReport>& per_pair);
  void add_reactions(const Reactions& r, double t);
};

}  // namespace tactus::solver

namespace tactus::solver {
struct RunSummary;
// run.json (keys from core/contracts.hpp run_json).
nlohmann::json run_json(const Scenario& sc, const Model& model, const ExplicitSolver& solver, const RunSummary& summary, const RunPeaks& peaks,
                        const nlohmann::json& failure);
}  // namespace tactus::solver
