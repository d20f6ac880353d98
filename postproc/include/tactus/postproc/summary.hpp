#pragma once
// The report's numbers (summary.json / summary.md): peak von Mises per material over the output
// states, peak contact pressure (every step, from the history, and at the output states), largest
// contact area, peak contact force, energy balance, and the run's steps, time step and wall time.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "tactus/postproc/results.hpp"

namespace tactus::postproc {

struct PeakAt {
  double value = 0, time = 0;
  std::array<double, 3> position{0, 0, 0};  // current (deformed) position, m
  long index = -1;                          // 1-based node or element of the state files, -1 if none
  std::string body;                         // the body it lies on (run.json bodies), when known
};

struct MaterialPeak {
  std::string material;
  PeakAt von_mises;  // Pa, at an element centroid
};

// A support's reaction (run.json reactions): its largest |R| over the run and R at the end.
struct ReactionSummary {
  std::string name;
  double peak = 0, peak_time = 0;
  std::array<double, 3> peak_force{0, 0, 0}, final_force{0, 0, 0}, final_moment{0, 0, 0};
};

struct FrameSummary {
  double time = 0;
  std::string file;
  std::vector<double> von_mises_max;  // per material index
  double contact_pressure_max = 0;    // Pa
  std::size_t contact_nodes = 0;      // nodes with pressure > 0
  double contact_force = 0;           // N, from the history row nearest in time (0 without contact)
};

struct Summary {
  std::string status, message;
  std::size_t steps = 0, nodes = 0, tets = 0;
  double end_time = 0, dt_min = 0, dt_max = 0, wall_time = 0, stress_seconds = 0, contact_seconds = 0;
  double initial_energy = 0, initial_kinetic = 0, balance_error = 0, contact_work_normal = 0, contact_work_friction = 0;
  std::vector<MaterialPeak> von_mises;  // over the output states
  bool contact_occurred = false;
  PeakAt peak_pressure_steps;    // every step (history): includes first-touch impulses
  PeakAt peak_pressure_outputs;  // at the output states (what the pictures show)
  PeakAt largest_area, peak_force;
  std::vector<ReactionSummary> reactions;  // one per [[boundary]]
  // hgo tissue: the largest isochoric fibre stretch sqrt(J4bar) over the output states (its
  // element centroid), the family (1 or 2) and that element's fibre stress von Mises; value 0: no fibres.
  PeakAt fibre_stretch;
  int fibre_family = 0;
  double fibre_stress_there = 0;
  // Per directed contact pair (run.json contact.pairs): its peaks over the run.
  struct PairPeak {
    std::string name;
    double force = 0, force_time = 0, area = 0, pressure = 0;
  };
  std::vector<PairPeak> contact_pairs;
  // Mass scaling (run.json mass_scaling), when it was on: the floor and each body's added mass.
  double minimum_time_step = 0;
  struct AddedMass {
    std::string body;
    double added = 0, fraction = 0;
  };
  std::vector<AddedMass> added_mass;
  // The grasp (run.json joints.grasp), when the run had one: the grip and the share of it each
  // hand region and digit carries at the end.
  struct GripShare {
    std::string name, digit;
    double force = 0, share = 0, area = 0, peak_pressure = 0, averaged_peak_pressure = 0;
  };
  struct Grasp {
    bool on = false, quasi_static = true;
    std::string handle;
    double target = 0, final_grip = 0, max_kinetic_ratio = 0, hold_from = 0, sensor_area = 0;
    std::vector<GripShare> regions, digits;
  } grasp;
  std::vector<FrameSummary> frames;
  std::vector<std::string> missing;   // output states listed but gone (Results::missing)
  std::vector<std::string> pictures;  // file names in the report folder
  std::string interactive;            // the interactive report's page (index.html), when written
};

Summary summarize(const Results& results);
std::string summary_json(const Summary& s);
std::string summary_markdown(const Summary& s);

}  // namespace tactus::postproc
