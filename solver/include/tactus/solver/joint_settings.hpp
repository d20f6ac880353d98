#pragma once
// What the joint drive takes ([skeleton], [[joint]] and [grasp] of scenario.toml, or set in code):
// plain structs (joint_drive.hpp moves the bones by them). A skeleton (core/skeleton.hpp) names
// the bones of one body and the joints between them; each bone is that body's rigid piece (or
// pieces) meshed from the bone's label, and moves by forward kinematics down its chain.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "tactus/core/skeleton.hpp"

namespace tactus::solver {

// [[joint]]: one joint's angles added to the mesh's posture, as functions of time:
// q(t) = angle x curve(t). A posture cannot jump, so the curve starts at 0.
struct JointSpec {
  std::string name;
  double flexion = 0;    // deg, towards the palm
  double abduction = 0;  // deg, about the joint's abduction axis
  std::string curve;     // [curves] name; required
};

// [grasp]: a torque-driven grip, as the flexor tendons close the fingers. Every joint of the
// skeleton that no [[joint]] drives and whose kind has a weight gets the flexion torque
// tau_j = s(t) w_kind; s is the output of a PI loop on the total grip force (the normal contact
// forces between the handle and the other bodies) against the target, ramped from 0 over
// ramp_time and held after.
struct GraspSpec {
  std::string handle;        // body; empty: no grasp
  double target_force = 0;   // N
  double ramp_time = 0.05;   // s
  double gain_p = 2e-3;      // N m of drive per N of grip error
  double gain_i = 0.2;       // N m per N s
  double max_torque = 1.0;   // N m: the largest drive scale s
  double flexion_min = -10;  // deg: each torque-driven joint's stops
  double flexion_max = 90;   // deg
  double weight_mcp = 1.0;   // finger metacarpophalangeal
  double weight_pip = 0.75;  // proximal interphalangeal
  double weight_dip = 0.5;   // distal interphalangeal
  double weight_cmc = 0.0;   // a finger's carpometacarpal (nearly immobile: held)
  double weight_thumb_cmc = 0.8, weight_thumb_mcp = 0.6, weight_thumb_ip = 0.4;
  // Where the handle goes (model building): its bounding box's centre to this point of the palm
  // frame (across, along, out of the palm; core/skeleton.hpp), its longest side turned across
  // the palm. Unset: the handle body stays where its own keys put it.
  std::optional<Vec3> handle_centre;
  // The handle on a rail along the palm frame's normal (bodies.rigid_guide set to it): it can only
  // move towards or away from the palm, as a grip dynamometer's handle, so the palm reacts what
  // the fingers squeeze. The handle must be free (no rigid_velocity).
  bool handle_guided = false;
  bool on() const { return !handle.empty(); }
};

// The drive as the model carries it (model_build.cpp fills it): the skeleton placed like its
// body, the kinematic joints by index with their angles in radians, the grasp's weights per
// skeleton joint (0: held unless kinematic) and the contact entries whose force is the grip.
struct JointDriveSetup {
  Skeleton skeleton;
  std::string file;  // where the skeleton came from, for messages
  std::size_t body = 0;
  struct Kinematic {
    std::size_t joint = 0;
    double flexion = 0, abduction = 0;  // rad
    std::int32_t curve = -1;
  };
  std::vector<Kinematic> kinematic;
  GraspSpec grasp;
  std::vector<double> torque_weight;  // per skeleton joint
  std::vector<int> grip_entries;      // [[contact]] indices between the handle and another body
  bool on() const { return !skeleton.bones.empty(); }
};

// The weight [grasp] gives a joint by its kind, the part of its name before '_' (mcp_index,
// pip_middle, ip_thumb, cmc_thumb): -1 when the kind has none.
double grasp_weight(const GraspSpec& grasp, const std::string& joint_name);

}  // namespace tactus::solver
