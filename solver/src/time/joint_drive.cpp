// The bones moved by their joints (joint_drive.hpp): kinematic angles, the grasp's torque-driven
// angles in reduced coordinates, and the PI loop on the grip force.
#include "tactus/solver/joint_drive.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/state_file.hpp"

namespace tactus::solver {

double grasp_weight(const GraspSpec& g, const std::string& joint) {
  const std::size_t cut = joint.find('_');
  const std::string kind = joint.substr(0, cut), digit = cut == std::string::npos ? "" : joint.substr(cut + 1);
  if (digit == "thumb") {
    if (kind == "cmc") return g.weight_thumb_cmc;
    if (kind == "mcp") return g.weight_thumb_mcp;
    if (kind == "ip") return g.weight_thumb_ip;
    return -1;
  }
  if (kind == "mcp") return g.weight_mcp;
  if (kind == "pip") return g.weight_pip;
  if (kind == "dip") return g.weight_dip;
  if (kind == "cmc") return g.weight_cmc;
  return -1;
}

namespace {

Vec3d eigen(const Vec3& v) { return {v[0], v[1], v[2]}; }
Mat3 rotation_of(const RigidTransform& t) { return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(t.rotation.data()); }
constexpr double kDeg = M_PI / 180;

std::size_t bone_index(const Skeleton& s, const std::string& name) {
  for (std::size_t b = 0; b < s.bones.size(); ++b)
    if (s.bones[b].name == name) return b;
  return s.bones.size();
}

}  // namespace

bool counts_in_grip(const ContactPair& pair, const std::vector<int>& entries) {
  return (pair.report_sign > 0 || pair.edge_pass) && std::find(entries.begin(), entries.end(), pair.entry) != entries.end();
}

JointDrive::JointDrive(const Model& model, RigidBodies& rigid) {
  const JointDriveSetup& setup = model.joint_drive;
  skeleton_ = setup.skeleton, file_ = setup.file, grasp_ = setup.grasp, grip_entries_ = setup.grip_entries;
  const std::size_t nb = skeleton_.bones.size(), nj = skeleton_.joints.size();
  const std::string& body = model.bodies[setup.body].name;
  // Each rigid piece of the body to the bone whose label its tets carry.
  pieces_.assign(nb, {});
  for (std::size_t k = 0; k < rigid.bodies().size(); ++k) {
    const RigidBody& piece = rigid.bodies()[k];
    if (piece.body != setup.body) continue;
    if (piece.prescribed)
      throw InputError(model.source, "bodies.rigid_velocity", "one motion for the bones of body '" + body + "': its [skeleton] or rigid_velocity",
                       "both");
    std::vector<std::size_t> bones;
    for (std::int32_t g : piece.groups)
      for (std::size_t b = 0; b < nb; ++b)
        if (skeleton_.bones[b].label == g) bones.push_back(b);
    // Roots fused in the mesh (carpals a coarse mesh bridges) are held together: nothing turns them.
    const bool all_roots = std::all_of(bones.begin(), bones.end(), [&](std::size_t b) { return skeleton_.bones[b].parent.empty(); });
    if (bones.size() > 1 && all_roots) {
      for (std::size_t b : bones) fused_roots_.push_back(b);
      loose_pieces_.push_back(k);
      continue;
    }
    if (bones.size() > 1) {
      std::ostringstream f;
      f << "one rigid piece, " << piece.name << ", holds bones";
      for (std::size_t b : bones) f << " '" << skeleton_.bones[b].name << "' (group " << skeleton_.bones[b].label << ")";
      f << ": they touch in the mesh";
      throw InputError(file_, "bones", "bones meshed apart, each its own rigid piece, for the joints between them to turn", f.str());
    }
    if (bones.empty()) {
      loose_pieces_.push_back(k);
    } else {
      pieces_[bones.front()].push_back(k);
    }
  }
  for (std::size_t b = 0; b < nb; ++b)
    if (pieces_[b].empty() && std::find(fused_roots_.begin(), fused_roots_.end(), b) == fused_roots_.end())
      throw InputError(file_, "bone '" + skeleton_.bones[b].name + "'",
                       "a rigid piece of body '" + body + "' meshed from its label " + std::to_string(skeleton_.bones[b].label) +
                           " (a material of type rigid on that physical group)",
                       "none");
  // Per joint: its proximal bone and the bones beyond it (the distal bone's subtree).
  proximal_bone_.resize(nj), distal_.assign(nj, {});
  for (std::size_t j = 0; j < nj; ++j) {
    const SkeletonJoint& joint = skeleton_.joints[j];
    proximal_bone_[j] = bone_index(skeleton_, joint.proximal);
    std::vector<std::string> open{joint.distal};
    while (!open.empty()) {
      const std::string name = open.back();
      open.pop_back();
      distal_[j].push_back(bone_index(skeleton_, name));
      for (const SkeletonBone& b : skeleton_.bones)
        if (b.parent == name) open.push_back(b.name);
    }
  }
  kinematic_.assign(nj, 0);
  kinematic_spec_ = setup.kinematic;
  for (const auto& k : kinematic_spec_) kinematic_[k.joint] = 1;
  weight_ = setup.torque_weight;
  weight_.resize(nj, 0.0);
  flexion_.assign(nj, 0.0), flexion_step_.assign(nj, 0.0), flexion_rate_.assign(nj, 0.0), abduction_.assign(nj, 0.0),
      generalised_force_.assign(nj, 0.0);
  for (const SkeletonJoint& j : skeleton_.joints) angles_.push_back({j.name, 0, 0});
  // Every piece of the body is prescribed from now on: the bones each step, the rest held.
  for (std::size_t k : loose_pieces_) rigid.prescribe(k, RigidMotion{});
  for (const auto& list : pieces_)
    for (std::size_t k : list) rigid.prescribe(k, RigidMotion{});
  std::size_t driven = 0;
  for (std::size_t j = 0; j < nj; ++j) driven += torque_driven(j) ? 1 : 0;
  log::info() << "joint drive: " << nb << " bones of body '" << body << "' (" << loose_pieces_.size() << " other rigid pieces held, "
              << fused_roots_.size() << " roots fused in them), " << kinematic_spec_.size() << " joints by angle"
              << (grasp_.on() ? ", " + std::to_string(driven) + " by the grasp's torque to " + std::to_string(grasp_.target_force) + " N" : "");
}

void JointDrive::control(double time, double dt, const std::vector<PairStepReport>& pairs, const std::vector<ContactPair>& pair_info) {
  // The grip: the normal forces of the handle's contact entries in the last contact step (a
  // two_pass entry's second pass sees the same interface and is left out).
  grip_ = 0;
  for (std::size_t p = 0; p < pairs.size() && p < pair_info.size(); ++p) {
    if (counts_in_grip(pair_info[p], grip_entries_)) grip_ += pairs[p].normal_force;
  }
  const double ramp = grasp_.ramp_time > 0 ? std::min(1.0, time / grasp_.ramp_time) : 1.0;
  target_now_ = grasp_.target_force * ramp;
  // PI with anti-windup: the integral does not grow into a saturated drive.
  const double error = target_now_ - grip_;
  const double unclamped = grasp_.gain_p * error + grasp_.gain_i * (integral_ + error * dt);
  if (!((unclamped >= grasp_.max_torque && error > 0) || (unclamped <= 0 && error < 0))) integral_ += error * dt;
  scale_ = std::clamp(grasp_.gain_p * error + grasp_.gain_i * integral_, 0.0, grasp_.max_torque);
  // A target the hand cannot reach: the drive at its largest, or every driven joint at its stop,
  // for a whole ramp_time after the ramp, with the grip short by more than 3 %.
  bool all_stopped = true, any = false;
  for (std::size_t j = 0; j < flexion_.size(); ++j)
    if (torque_driven(j)) any = true, all_stopped = all_stopped && flexion_[j] >= grasp_.flexion_max * kDeg - 1e-12;
  const bool saturated = scale_ >= grasp_.max_torque;
  if (time > grasp_.ramp_time && grip_ < 0.97 * grasp_.target_force && (saturated || (any && all_stopped))) {
    if (stuck_since_ < 0) stuck_since_ = time;
    if (time - stuck_since_ >= std::max(grasp_.ramp_time, 10 * dt)) {
      std::ostringstream o;
      o << "grip target " << grasp_.target_force << " N not reached: the grip is " << grip_ << " N at t = " << time << " s with "
        << (saturated ? "the drive at grasp.max_torque = " + std::to_string(grasp_.max_torque) + " N m"
                      : "every torque-driven joint at its stop grasp.flexion_max = " + std::to_string(grasp_.flexion_max) + " deg")
        << " since t = " << stuck_since_ << " s (raise grasp.max_torque, or move the handle into the hand's reach)";
      throw NumericalError(o.str());
    }
  } else {
    stuck_since_ = -1;
  }
}

void JointDrive::advance_torque_joints(const RigidBodies& rigid, const std::vector<RigidTransform>& now, double dt, double dtbar, double c_minus,
                                       double c_plus) {
  const double lo = grasp_.flexion_min * kDeg, hi = grasp_.flexion_max * kDeg;
  for (std::size_t j = 0; j < flexion_.size(); ++j) {
    if (!torque_driven(j)) continue;
    const RigidTransform& parent = now[proximal_bone_[j]];
    const Vec3d a = eigen(parent.turn(skeleton_.joints[j].flexion_axis)), p = eigen(parent.apply(skeleton_.joints[j].centre));
    double Q = 0, inertia = 0;
    for (std::size_t b : distal_[j])
      for (std::size_t k : pieces_[b]) {
        const RigidBody& r = rigid.bodies()[k];
        const Vec3d arm = r.centre - p;
        Q += a.dot(r.moment + arm.cross(r.force));
        inertia += a.dot(r.inertia() * a) + r.mass * a.cross(arm).squaredNorm();
      }
    generalised_force_[j] = Q;
    // The half-step kick and drift of the angle (explicit.hpp's, with the nodes' mass damping).
    double rate = (c_minus * flexion_rate_[j] + dtbar * (Q + torque(j)) / inertia) * c_plus;
    double q = flexion_[j] + dt * rate;
    if (q > hi || q < lo) {  // an inelastic stop
      q = std::clamp(q, lo, hi);
      rate = (q - flexion_[j]) / dt;
    }
    flexion_rate_[j] = rate, flexion_[j] = q;
  }
}

void JointDrive::steer(const Model& model, RigidBodies& rigid, const std::vector<PairStepReport>& pairs, const std::vector<ContactPair>& pair_info,
                       double time, double t_next, double dt, double dtbar, double c_minus, double c_plus) {
  flexion_step_ = flexion_;
  auto placements = [&] {
    for (std::size_t j = 0; j < angles_.size(); ++j) angles_[j].flexion = flexion_[j], angles_[j].abduction = abduction_[j];
    return forward_kinematics(skeleton_, angles_);
  };
  if (grasp_.on()) {
    control(time, dt, pairs, pair_info);
    advance_torque_joints(rigid, placements(), dt, dtbar, c_minus, c_plus);
  }
  for (const auto& k : kinematic_spec_) {
    const double c = model.curve_at(k.curve, t_next);
    flexion_[k.joint] = k.flexion * c, abduction_[k.joint] = k.abduction * c;
  }
  // Every bone to its placement at t^{n+1}: the motion over the step that lands there (the
  // placement is recomputed from the angles each step, so round-off does not drift).
  const std::vector<RigidTransform> next = placements();
  for (std::size_t b = 0; b < pieces_.size(); ++b) {
    const Mat3 R = rotation_of(next[b]);
    for (std::size_t k : pieces_[b]) {
      const RigidBody& r = rigid.bodies()[k];
      RigidMotion motion;
      motion.velocity = (eigen(next[b].apply({r.centre0[0], r.centre0[1], r.centre0[2]})) - r.centre) / dt;
      const Eigen::AngleAxisd turn(Mat3(R * r.rotation.transpose()));
      motion.angular_velocity = turn.angle() / dt * turn.axis();
      rigid.prescribe(k, motion);
    }
  }
}

void JointDrive::observe(double time, double kinetic, double internal) {
  if (grasp_.on() && time >= grasp_.ramp_time && internal > 0) max_ratio_hold_ = std::max(max_ratio_hold_, kinetic / internal);
}

void JointDrive::checkpoint(StateArchive& a) {
  const std::size_t nj = flexion_.size();
  for (auto [name, v] : {std::pair<const char*, std::vector<double>*>{"flexion", &flexion_},
                         {"flexion_rate", &flexion_rate_},
                         {"abduction", &abduction_},
                         {"generalised_force", &generalised_force_}})
    a.io(std::string("joints.") + name, *v, nj);
  for (auto [name, x] : {std::pair<const char*, double*>{"integral", &integral_},
                         {"scale", &scale_},
                         {"grip", &grip_},
                         {"target", &target_now_},
                         {"max_ratio_hold", &max_ratio_hold_},
                         {"stuck_since", &stuck_since_}})
    a.io(std::string("joints.") + name, *x);
}

}  // namespace tactus::solver
