#pragma once
// Loading: time curves, prescribed motions, follower pressures and the reactions of the supports.
//
// - A prescribed displacement d(t) = value x curve(t) is met exactly at every step: the dof's
//   velocity over the step is (d(t^{n+1}) - u^n) / dt. A prescribed velocity v(t) = value x
//   curve(t) moves the dof by value x integral of the curve, also exact at every step.
// - A pressure p(t) acts on the current surface: node a of a triangle gets -p n A / 3, with n A
//   the current area-weighted outward normal (a follower load; its work is counted with gravity's
//   in the external work).
// - The reaction of a support is the force it applies to the body to hold the prescribed motion:
//   R = m (v^{n+1/2} - v_free^{n+1/2}) / (dtbar c_plus) per constrained dof (c_plus the alpha
//   factor of the update), where v_free includes every other force on the node (internal,
//   external, mass-proportional damping). So the reaction includes the alpha-damping force of the
//   constrained nodes (the support holds it too), and not a contact reaction on a constrained
//   node (contact sees those nodes as immovable).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "tactus/core/vec3.hpp"

namespace tactus::solver {

// A [[boundary]] entry's reaction: its name and the point the moment is taken about.
struct BoundaryReactionSpec {
  std::string name;
  Vec3 moment_about{0, 0, 0};
};

// A [[load]] pressure: triangles in internal node numbering, each oriented with its normal out of
// the body (the side without the triangle's tet).
struct PressureLoad {
  std::string name;                     // "load[k] body/group"
  std::vector<std::int32_t> triangles;  // 3 per triangle
  double pressure = 0;
  std::int32_t curve = -1;
};

// The reaction force and moment of every boundary at one time.
struct Reactions {
  std::vector<double> force, moment;  // 3 per boundary
};

}  // namespace tactus::solver
