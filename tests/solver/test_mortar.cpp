// solver/contact, mortar method: the contact patch test (Taylor & Papadopoulos 1991; in 3-D as in
// Puso & Laursen 2004). Two elastic blocks of the same material and footprint, non-matching meshes
// (element-size ratio 1.5, slave finer and slave coarser), stacked on rollers and compressed by a
// ramped displacement of the top face, held until at rest: the stress is uniform, so every
// contact node's pressure must equal the top block's stress, |R_top| / A, within 1 %.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/model.hpp"
#include "temp_dir.hpp"

using namespace tactus;
using namespace tactus::solver;

namespace {

struct PatchResult {
  double exact = 0, lowest = 0, highest = 0, kinetic_ratio = 0;
  std::size_t nodes = 0;
};

PatchResult patch_test(int master_cells, int slave_cells, const std::string& method) {
  testkit::TempDir dir;
  const double L = 0.02, H = 0.01, E = 1e6;
  write_msh(dir.path() / "lower.msh", samples::make_box_mesh(master_cells, master_cells, 2, L, L, H));
  write_msh(dir.path() / "upper.msh", samples::make_box_mesh(slave_cells, slave_cells, 2, L, L, H, {0, 0, H}));
  Scenario sc;
  sc.file = dir.path() / "patch.toml";
  sc.run.end_time = 0.2;
  sc.damping.alpha = 3000;
  sc.materials["m"] = MaterialInstance{"m", "linear_elastic", {{{"E", E}, {"nu", 0.3}, {"density", 1000}}, {}}};
  for (const char* name : {"lower", "upper"}) {
    BodySpec b;
    b.name = name;
    b.mesh = dir.path() / (std::string(name) + ".msh");
    b.materials["*"] = "m";
    sc.bodies.push_back(b);
  }
  sc.curves["ramp"] = CurveSpec{"ramp", {}, {}, true, 0.0, 0.01};
  auto bc = [&](const std::string& body, const std::string& group, std::array<bool, 3> comps, const std::string& name) {
    BoundarySpec b;
    b.body = body, b.group = group, b.type = "fixed", b.components = comps, b.name = name;
    return b;
  };
  sc.boundaries.push_back(bc("lower", "zmin", {false, false, true}, "base"));
  for (const char* body : {"lower", "upper"}) {  // rollers on the two symmetry planes
    sc.boundaries.push_back(bc(body, "xmin", {true, false, false}, std::string(body) + "_x"));
    sc.boundaries.push_back(bc(body, "ymin", {false, true, false}, std::string(body) + "_y"));
  }
  BoundarySpec top = bc("upper", "zmax", {false, false, true}, "top");
  top.type = "displacement", top.displacement = {0, 0, -2e-5}, top.curve = "ramp";  // 0.1 % strain
  sc.boundaries.push_back(top);
  ContactSpec c;
  c.slave_body = "upper", c.slave_surface = "zmin", c.master_body = "lower", c.master_surface = "zmax", c.method = method;
  sc.contacts.push_back(c);
  sc.contact_solver.tolerance = 1e-10;
  sc.contact_solver.max_iterations = 2000;
  const Model m = build_model(sc);
  ExplicitSolver s(m, sc.run, sc.damping);
  while (true) {
    s.advance_velocity();
    if (s.finished() || (s.time() > 0.01 && s.energies().kinetic <= 1e-6 * s.energies().internal)) break;
    s.advance_position();
  }
  PatchResult r;
  r.kinetic_ratio = s.energies().kinetic / s.energies().internal;
  r.exact = std::abs(s.reactions().force[3 * (sc.boundaries.size() - 1) + 2]) / (L * L);
  const ContactRows& rows = s.contact().rows();
  r.lowest = 1e300, r.highest = -1e300;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const double pk = (rows.reaction[3 * k] * rows.normal[3 * k] + rows.reaction[3 * k + 1] * rows.normal[3 * k + 1] +
                       rows.reaction[3 * k + 2] * rows.normal[3 * k + 2]) /
                      rows.area[k];
    r.lowest = std::min(r.lowest, pk), r.highest = std::max(r.highest, pk);
    ++r.nodes;
  }
  std::printf(
      "%s, master %d x %d cells, slave %d x %d: %zu contact nodes, pressure %.2f .. %.2f Pa vs the top stress %.2f Pa (%+.3f %% .. %+.3f %%), "
      "kinetic/strain %.1e\n",
      method.c_str(), master_cells, master_cells, slave_cells, slave_cells, r.nodes, r.lowest, r.highest, r.exact, 100 * (r.lowest / r.exact - 1),
      100 * (r.highest / r.exact - 1), r.kinetic_ratio);
  return r;
}

}  // namespace

TEST(Mortar, ContactPatchTestSlaveFinerAndSlaveCoarser) {
  for (const auto& [lower, upper] : {std::pair{6, 9}, std::pair{9, 6}}) {
    const PatchResult r = patch_test(lower, upper, "mortar");
    EXPECT_LE(r.kinetic_ratio, 1e-6);
    EXPECT_EQ(r.nodes, static_cast<std::size_t>((upper + 1) * (upper + 1)));
    EXPECT_NEAR(r.lowest, r.exact, 0.01 * r.exact);
    EXPECT_NEAR(r.highest, r.exact, 0.01 * r.exact);
  }
  // For the record (not asserted): node-to-surface on the same meshes.
  patch_test(6, 9, "node_to_surface");
}
