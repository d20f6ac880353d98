#pragma once
// The grip's regions (docs/design.md, "Joints and the grasp"): where on the hand the handle's
// load goes. Each skin node of the handle's contact entries belongs to the region of its nearest
// bone in the reference configuration:
//   - a phalanx (a bone that is neither a root nor named "metacarpal_..."): the region is that
//     bone, named as the skeleton names it ("distal_phalanx_index"); its digit is the chain's
//     metacarpal ("index"), or the bone below the root on a chain without one;
//   - a metacarpal or a carpal: the palm, in zones by the nearest metacarpal: thenar over the
//     thumb's, hypothenar over the little finger's, central over the others.
// Per region: the normal contact force of the handle's rows, the tributary area of the pressed
// skin nodes, the largest nodal pressure of the handle's rows alone (self-contact in the palm
// folds is not the handle's) and, at output times, that pressure averaged over a sensor cell.
#include <cstdint>
#include <string>
#include <vector>

#include "tactus/solver/contact.hpp"
#include "tactus/solver/joint_drive.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/rigid.hpp"

namespace tactus::solver {

class GripRegions {
 public:
  GripRegions(const Model& model, const RigidBodies& rigid, const JointDrive& drive, const ContactSolver& contact);

  const std::vector<std::string>& names() const { return names_; }             // per region
  const std::vector<std::size_t>& digit() const { return digit_; }             // per region: its digit (digits())
  const std::vector<std::string>& digits() const { return digits_; }           // "thumb", ..., and "palm" last
  const std::vector<std::int32_t>& region_of_node() const { return region_; }  // per model node, -1: none

  // The sums of the last contact step (ContactSolver::rows after correct_velocities).
  void sum(const ContactSolver& contact);
  const std::vector<double>& force() const { return force_; }              // N, per region
  const std::vector<double>& area() const { return area_; }                // m^2, per region
  const std::vector<double>& peak_pressure() const { return peak_; }       // Pa, per region
  const std::vector<double>& digit_force() const { return digit_force_; }  // N, per digit
  // The handle's pressure averaged over `sensor_area` (the run's pressure_average_area), per region.
  std::vector<double> averaged_peak_pressure(const Model& model, const double* u, double sensor_area) const;

 private:
  std::vector<int> entries_;
  std::vector<std::string> names_, digits_;
  std::vector<std::size_t> digit_;
  std::vector<std::int32_t> region_;
  std::vector<std::int32_t> surface_;  // the handle's slave triangles (3 nodes each)
  std::vector<double> force_, area_, peak_, digit_force_;
  std::vector<double> node_area_;                   // per model node, its tributary area in the handle's skin pass
  std::vector<double> node_force_, node_pressure_;  // per model node, the handle's rows only (kept: no allocation per sum)
  std::vector<char> is_pressed_;
  std::vector<std::int32_t> pressed_;  // the nodes node_force_ holds
};

}  // namespace tactus::solver
