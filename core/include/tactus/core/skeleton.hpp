#pragma once
// The hand's skeleton, as the stages pass it on: tactus-phantom writes its truth (joints.json),
// tactus-mesh skeleton extracts one from a mesh's bone groups (skeleton.json), and the solver's
// [[joint]] keys drive the bones through it. Bones carry their parent, joints a centre, a flexion
// axis and an abduction axis, all in the mesh frame (metres).
//
// Conventions. A joint turns its distal bone, and everything beyond it, about its centre. A
// positive flexion turns the distal bone towards the palm: the flexion axis a is the bone's long
// axis d crossed with the palm normal n (pointing out of the palm), a = d x n / |d x n|, so that
// a x d = n (right-hand rule). The abduction axis is n made orthogonal to a; a positive abduction
// turns the bone about it by the right-hand rule. The roots (the carpals) have no parent: they
// move with the forearm.
#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "tactus/core/vec3.hpp"

namespace tactus {

struct SkeletonBone {
  std::string name;
  std::string parent;  // empty: a root
  int label = -1;      // its label in the labels volume and physical group in the mesh (-1: unknown)
  Vec3 centroid{};     // of its volume
  Vec3 long_axis{};    // unit, from its base towards its head (distal)
  double length = 0;   // along the long axis
};

struct SkeletonJoint {
  std::string name;                       // "mcp_index", "pip_index", "ip_thumb", ...
  std::string proximal, distal;           // bone names; the distal bone's parent is the proximal one
  Vec3 centre{};                          // the proximal bone's head centre (docs/design.md, the skeleton)
  Vec3 flexion_axis{}, abduction_axis{};  // unit, orthogonal
};

struct Skeleton {
  std::string source;  // what made it
  Vec3 palm_normal{};  // unit, out of the palm
  std::vector<SkeletonBone> bones;
  std::vector<SkeletonJoint> joints;

  // nullptr when absent.
  const SkeletonBone* bone(const std::string& name) const;
  const SkeletonJoint* joint(const std::string& name) const;
  // The joint whose distal bone is `bone` (nullptr for a root).
  const SkeletonJoint* joint_into(const std::string& bone) const;
};

// A rigid placement x -> rotation x + translation.
struct RigidTransform {
  std::array<double, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major
  Vec3 translation{};
  Vec3 apply(const Vec3& x) const;
  Vec3 turn(const Vec3& d) const;                         // rotation only
  RigidTransform then(const RigidTransform& next) const;  // next(this(x))
};

// The rotation by `angle` (radians) about the unit `axis` through `centre` (Rodrigues).
RigidTransform rotation_about(const Vec3& centre, const Vec3& axis, double angle);

// Joint angles in radians, by joint name; joints not named stay at 0.
struct JointAngles {
  std::string joint;
  double flexion = 0, abduction = 0;
};

// Forward kinematics: the placement of every bone (in skeleton.bones order) for the joint angles.
// Each joint's motion is its abduction after its flexion, both about axes through its centre in
// the parent's frame, composed down the chain from the roots: T_bone = T_parent o J.
// InputError naming the joint when an angle names no joint.
std::vector<RigidTransform> forward_kinematics(const Skeleton& skeleton, const std::vector<JointAngles>& angles);

// The palm frame: origin the mean of the four fingers' MCP joint centres (joints mcp_<digit>,
// the thumb's left out), `along` the mean long axis of their metacarpals made orthogonal to the
// palm normal (towards the fingers), `across` = along x normal (for a right hand seen from the
// palm: index towards little finger), `normal` out of the palm. InputError naming `file` when
// the skeleton has no finger MCP joint.
struct PalmFrame {
  Vec3 origin{}, across{}, along{}, normal{};
  Vec3 point(const Vec3& local) const;  // origin + local[0] across + local[1] along + local[2] normal
};
PalmFrame palm_frame(const Skeleton& skeleton, const std::string& file);

// Checks what a reader relies on: unique names, every parent a bone, every non-root bone entered
// by exactly one joint from its parent, unit orthogonal axes, no cycle. InputError naming `file`
// and the bone or joint otherwise.
void validate_skeleton(const Skeleton& skeleton, const std::string& file);

std::string skeleton_json(const Skeleton& skeleton);
void write_skeleton(const std::filesystem::path& file, const Skeleton& skeleton);
Skeleton read_skeleton(const std::filesystem::path& file);

}  // namespace tactus
