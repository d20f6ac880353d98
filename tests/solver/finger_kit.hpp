#pragma once
// The synthetic finger of the grasp tests (joint_drive.hpp): a 72 x 18 x 18 mm box of soft tissue
// along x, its palm side at z = 0, with three rigid bones inside (6 x 6 mm cross-sections on the
// finger's axis y = 0, z = 9 mm, 6 mm apart): a held root x 3..18 mm, a proximal segment 24..42
// and a distal one 48..66, joined at x = 21 mm (mcp_finger) and 45 mm (pip_finger). The palm
// normal is -z, so both joints flex about +y. A rigid cylinder along y (the handle) can lie under
// it. Built in memory and written as the files a scenario reads.
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "scenario_kit.hpp"
#include "tactus/core/mesh.hpp"
#include "tactus/core/skeleton.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/scenario.hpp"

namespace tactus::testkit {

struct FingerBone {
  const char* name;
  int label;
  double x0, x1;  // m
};
inline constexpr std::array<FingerBone, 3> kFingerBones{
    {{"metacarpal_finger", 2, 0.003, 0.018}, {"proximal_phalanx_finger", 3, 0.024, 0.042}, {"middle_phalanx_finger", 4, 0.048, 0.066}}};
inline constexpr double kFingerAxisZ = 0.009;

// one_cell_joint_gap: the proximal phalanx reaches 3 mm further, so one cell (3 mm) separates it
// from the middle phalanx: tissue tets there have all four nodes on the two bones (joint gaps).
inline TetMesh finger_mesh(bool one_cell_joint_gap = false) {
  TetMesh m = samples::make_box_mesh(24, 6, 6, 0.072, 0.018, 0.018, {0, -0.009, 0});
  for (PhysicalGroup& g : m.groups)
    if (g.dim == 3) g.name = "tissue";
  for (const FingerBone& b : kFingerBones) m.groups.push_back({3, b.label, b.name});
  for (std::size_t e = 0; e < m.tets.size(); ++e) {
    Vec3 c{0, 0, 0};
    for (int v : m.tets[e]) c = c + 0.25 * m.nodes[static_cast<std::size_t>(v)];
    if (std::abs(c[1]) > 0.003 || c[2] < 0.006 || c[2] > 0.012) continue;
    for (const FingerBone& b : kFingerBones)
      if (c[0] > b.x0 && c[0] < b.x1 + (one_cell_joint_gap && b.label == kFingerBones[1].label ? 0.003 : 0.0)) m.tet_group[e] = b.label;
  }
  add_whole_boundary_group(m);
  return m;
}

inline Skeleton finger_skeleton() {
  Skeleton s;
  s.source = "the grasp tests' synthetic finger";
  s.palm_normal = {0, 0, -1};
  std::string parent;
  for (const FingerBone& b : kFingerBones) {
    s.bones.push_back({b.name, parent, b.label, {0.5 * (b.x0 + b.x1), 0, kFingerAxisZ}, {1, 0, 0}, b.x1 - b.x0});
    parent = b.name;
  }
  s.joints.push_back({"mcp_finger", kFingerBones[0].name, kFingerBones[1].name, {0.021, 0, kFingerAxisZ}, {0, 1, 0}, {0, 0, -1}});
  s.joints.push_back({"pip_finger", kFingerBones[1].name, kFingerBones[2].name, {0.045, 0, kFingerAxisZ}, {0, 1, 0}, {0, 0, -1}});
  return s;
}

// A rigid cylinder of radius r along y (length len, centred on y = 0) with its axis through
// (cx, ., cz): `sectors` wedges around the axis, `layers` along it, each wedge three tets split so
// that neighbouring wedges share their faces. Groups: volume 1 "handle", surface 2 "surface".
inline TetMesh cylinder_mesh(double r, double len, double cx, double cz, int sectors, int layers) {
  TetMesh m;
  const int ring = sectors + 1;  // the axis node, then the ring, per layer
  for (int l = 0; l <= layers; ++l) {
    const double y = -0.5 * len + len * l / layers;
    m.nodes.push_back({cx, y, cz});
    for (int s = 0; s < sectors; ++s) {
      const double t = 2 * M_PI * s / sectors;
      m.nodes.push_back({cx + r * std::cos(t), y, cz + r * std::sin(t)});
    }
  }
  auto node = [&](int l, int s) { return s < 0 ? l * ring : l * ring + 1 + (s % sectors); };
  auto add_tet = [&](std::array<int, 4> t) {
    const Vec3 a = m.nodes[static_cast<std::size_t>(t[0])];
    const Vec3 e1 = m.nodes[static_cast<std::size_t>(t[1])] - a, e2 = m.nodes[static_cast<std::size_t>(t[2])] - a,
               e3 = m.nodes[static_cast<std::size_t>(t[3])] - a;
    if (dot(cross(e1, e2), e3) < 0) std::swap(t[2], t[3]);
    m.tets.push_back(t);
    m.tet_group.push_back(1);
  };
  auto add_triangle = [&](std::array<int, 3> t, const Vec3& outward) {
    const Vec3 a = m.nodes[static_cast<std::size_t>(t[0])];
    if (dot(cross(m.nodes[static_cast<std::size_t>(t[1])] - a, m.nodes[static_cast<std::size_t>(t[2])] - a), outward) < 0) std::swap(t[1], t[2]);
    m.triangles.push_back(t);
    m.triangle_group.push_back(2);
  };
  for (int l = 0; l < layers; ++l)
    for (int s = 0; s < sectors; ++s) {
      // The wedge C0 A0 B0 / C1 A1 B1: both radial faces split along C0-X1, the outer one along A0-B1.
      const int C0 = node(l, -1), A0 = node(l, s), B0 = node(l, s + 1), C1 = node(l + 1, -1), A1 = node(l + 1, s), B1 = node(l + 1, s + 1);
      add_tet({C0, A0, B0, B1}), add_tet({C0, A0, B1, A1}), add_tet({C0, A1, B1, C1});
      const double t = 2 * M_PI * (s + 0.5) / sectors;
      const Vec3 out{std::cos(t), 0, std::sin(t)};
      add_triangle({A0, B0, B1}, out), add_triangle({A0, B1, A1}, out);
      if (l == 0) add_triangle({C0, A0, B0}, {0, -1, 0});
      if (l == layers - 1) add_triangle({C1, A1, B1}, {0, 1, 0});
    }
  m.groups = {{3, 1, "handle"}, {2, 2, "surface"}};
  return m;
}

// The finger's materials: bone rigid, tissue neo-Hookean (mu 0.3 MPa, bulk 3 MPa), the handle rigid.
inline void add_finger_materials(solver::Scenario& sc) {
  sc.materials["tissue"] = {"tissue", "neo_hookean", {{{"mu", 3e5}, {"bulk", 3e6}, {"density", 1100}}, {}}};
  sc.materials["bone"] = {"bone", "rigid", {{{"density", 2000}}, {}}};
}

// The finger as a scenario body with its skeleton (written to dir/finger_skeleton.json).
inline void add_finger(solver::Scenario& sc, const TempDir& dir, bool one_cell_joint_gap = false) {
  add_finger_materials(sc);
  solver::BodySpec finger = body_from_mesh(dir, "finger", finger_mesh(one_cell_joint_gap), "tissue");
  for (const FingerBone& b : kFingerBones) finger.materials[b.name] = "bone";
  sc.bodies.push_back(finger);
  write_skeleton(dir.path() / "finger_skeleton.json", finger_skeleton());
  sc.skeleton = solver::SkeletonSpec{"finger", dir.path() / "finger_skeleton.json"};
}

// The finger over the handle: a rigid cylinder of radius 10 mm along y under the proximal
// segment, 2 mm below the palm side, held; the skin against it by mortar with friction 0.3.
inline solver::Scenario grasp_scenario(const TempDir& dir, double target, double end_time) {
  solver::Scenario sc;
  sc.file = dir.path() / "grasp.toml";
  add_finger(sc, dir);
  solver::BodySpec handle = body_from_mesh(dir, "handle", cylinder_mesh(0.010, 0.030, 0.040, -0.012, 24, 4), "bone");
  handle.rigid_velocity = Vec3{0, 0, 0}, handle.rigid_angular_velocity = Vec3{0, 0, 0};
  sc.bodies.push_back(handle);
  solver::ContactSpec c;
  c.slave_body = "finger", c.slave_surface = "surface", c.master_body = "handle", c.master_surface = "surface", c.friction = 0.3;
  sc.contacts.push_back(c);
  sc.grasp.handle = "handle";
  sc.grasp.target_force = target;
  sc.grasp.ramp_time = 0.05;
  sc.grasp.max_torque = 5;
  sc.grasp.gain_p = 0.01;
  sc.grasp.gain_i = 3;
  sc.run.end_time = end_time;
  sc.damping.alpha = 200;
  return sc;
}

}  // namespace tactus::testkit
