#pragma once
// Joint-driven motion of a skeleton's bones (docs/design.md, "Joints and the grasp"). The bones
// are rigid pieces (rigid.hpp) prescribed every step, through RigidBodies::prescribe, to the
// placement forward kinematics (core/skeleton.hpp) gives for the joint angles at t^{n+1}: the
// soft tissue follows through the nodes it shares with them, and the support that moves a bone
// is its reaction. The roots (carpals) and any rigid piece of the body no bone claims are held.
//
// A joint's angle is kinematic ([[joint]]: q = angle x curve(t)) or, under [grasp], a degree of
// freedom in reduced coordinates: with a the joint's flexion axis and p its centre (carried by
// the proximal bone), the generalised force of everything acting on its distal subchain D is
//   Q = a . sum_{b in D} (M_b + (c_b - p) x F_b),
// F_b and M_b the tissue's, the loads' and (through the tissue) the contact's force and moment
// on bone b at t^n; the drive adds the tendon torque tau = s(t) w. The angle moves by the
// integrator's half-step kick and drift with the joint inertia of D about a,
//   I = sum_{b in D} (a . I_b a + m_b |a x (c_b - p)|^2),
// and the nodes' mass damping alpha: the diagonal of the chain's mass matrix. The coupling
// terms are left out: they change the transient, not the held equilibrium Q + tau = 0.
#include <cstdint>
#include <string>
#include <vector>

#include "tactus/solver/contact.hpp"
#include "tactus/solver/joint_settings.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/rigid.hpp"

namespace tactus {
class StateArchive;
}

namespace tactus::solver {

// Whether a contact pair's rows count in the grip: a pair of one of the handle's [[contact]]
// `entries`, but not a two_pass entry's second pass, which sees the same interface from the handle.
bool counts_in_grip(const ContactPair& pair, const std::vector<int>& entries);

class JointDrive {
 public:
  // Matches every bone to the rigid pieces of its body meshed from its label (physical group);
  // InputError naming the bone when it has none, or naming the bones when one piece holds two.
  JointDrive(const Model& model, RigidBodies& rigid);

  // Before the rigid kick of the step [time, t_next] (RigidBodies::sum_loads done): the grip
  // from the last contact step, the drive, the torque-driven angles' kick and drift, and every
  // bone piece prescribed to its placement at t_next. NumericalError when the grip target cannot
  // be reached (the drive at max_torque, or every driven joint at its stop, for ramp_time).
  void steer(const Model& model, RigidBodies& rigid, const std::vector<PairStepReport>& pairs, const std::vector<ContactPair>& pair_info, double time,
             double t_next, double dt, double dtbar, double c_minus, double c_plus);
  // After the step's energies at t^n: the largest kinetic / strain energy ratio during the hold
  // (t >= ramp_time).
  void observe(double time, double kinetic, double internal);

  bool grasp() const { return grasp_.on(); }
  const Skeleton& skeleton() const { return skeleton_; }
  double grip_force() const { return grip_; }
  double grip_target() const { return target_now_; }
  double drive_scale() const { return scale_; }                                        // s, N m
  const std::vector<double>& flexion() const { return flexion_; }                      // per skeleton joint, rad, at t^{n+1} once steered
  const std::vector<double>& flexion_at_step() const { return flexion_step_; }         // at t^n
  const std::vector<double>& generalised_force() const { return generalised_force_; }  // Q per joint at t^n, N m
  double torque(std::size_t joint) const { return scale_ * weight_[joint]; }
  bool torque_driven(std::size_t joint) const { return weight_[joint] > 0 && !kinematic_[joint]; }
  double max_kinetic_ratio_in_hold() const { return max_ratio_hold_; }
  const std::vector<int>& grip_entries() const { return grip_entries_; }                    // the handle's [[contact]] entries
  const std::vector<std::size_t>& pieces(std::size_t bone) const { return pieces_[bone]; }  // its rigid pieces
  const std::vector<std::size_t>& loose_pieces() const { return loose_pieces_; }            // held, no bone's own

  void checkpoint(StateArchive& archive);

 private:
  void control(double time, double dt, const std::vector<PairStepReport>& pairs, const std::vector<ContactPair>& pair_info);
  void advance_torque_joints(const RigidBodies& rigid, const std::vector<RigidTransform>& now, double dt, double dtbar, double c_minus,
                             double c_plus);

  Skeleton skeleton_;
  std::string file_;
  GraspSpec grasp_;
  std::vector<int> grip_entries_;
  std::vector<std::vector<std::size_t>> pieces_;  // per bone, its rigid pieces
  std::vector<std::size_t> loose_pieces_;         // the body's pieces no bone claims, or roots only: held
  std::vector<std::size_t> fused_roots_;          // roots meshed into one piece with another root
  std::vector<std::vector<std::size_t>> distal_;  // per joint, the bones beyond it
  std::vector<std::size_t> proximal_bone_;        // per joint
  std::vector<char> kinematic_;                   // per joint
  std::vector<JointDriveSetup::Kinematic> kinematic_spec_;
  std::vector<double> weight_;  // per joint: the torque law's w (0: held)
  // State: per joint flexion (rad) at t^n and its rate at t^{n-1/2}; abduction at t^n; the PI's
  // integral, drive and grip; the hold's ratio; how long the drive has been unable to reach.
  std::vector<double> flexion_, flexion_rate_, abduction_, generalised_force_, flexion_step_;
  double integral_ = 0, scale_ = 0, grip_ = 0, target_now_ = 0, max_ratio_hold_ = 0, stuck_since_ = -1;
  std::vector<JointAngles> angles_;  // scratch for forward kinematics
};

}  // namespace tactus::solver
