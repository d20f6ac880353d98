// solver/contact: the contact patch test (Taylor & Papadopoulos 1991; in 3-D as in Puso & Laursen
// 2004). Two elastic blocks of the same material and footprint, non-matching meshes (element-size
// ratio 1.5, slave finer and slave coarser; structured, and unstructured gmsh meshes whose
// boundary nodes differ), stacked on rollers and compressed by a ramped displacement of the top
// face, held until at rest: the stress is uniform, so every contact node's pressure must equal the
// top block's stress, |R_top| / A, within 1 % (mortar). Node to surface cannot pass it (printed),
// but must lose no node at the footprint's edges and corners.
#include <gtest/gtest.h>

#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "tactus/core/gmsh_session.hpp"

#include "gmsh_kit.hpp"
#include "scenario_kit.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/model_build.hpp"
#include "temp_dir.hpp"

using namespace tactus;
using namespace tactus::solver;

namespace {

struct PatchResult {
  double exact = 0, lowest = 0, highest = 0, kinetic_ratio = 0;
  double worst_gap = 0;   // the most negative gap of a contact row at rest, m
  std::size_t nodes = 0;  // contact rows at rest
  std::size_t slave_nodes = 0;
  double averaged = 0;  // the largest average over a 25 mm^2 disc (ContactSolver::averaged_peak_pressure)
};

constexpr double L = 0.02, H = 0.01;  // footprint and height of each block

// An unstructured gmsh mesh of the box [0, L]^2 x [z0, z0 + H] with elements of size h, its
// faces in the physical groups of samples::make_box_mesh ("xmin" .. "zmax", 11 .. 16).
TetMesh gmsh_box(double z0, double h, const char* name) {
  GmshSession session;
  gmsh::model::add(name);
  const int vol = gmsh::model::occ::addBox(0, 0, z0, L, L, H);
  gmsh::model::occ::synchronize();
  gmsh::model::addPhysicalGroup(3, {vol}, 1);
  gmsh::model::setPhysicalName(3, 1, "body");
  const double lo[3] = {0, 0, z0}, hi[3] = {L, L, z0 + H};
  testkit::tag_box_plane_faces(vol, lo, hi);
  gmsh::option::setNumber("Mesh.MeshSizeMin", h);
  gmsh::option::setNumber("Mesh.MeshSizeMax", h);
  gmsh::option::setNumber("Mesh.RandomSeed", 1);
  gmsh::model::mesh::generate(3);
  return tet_mesh_from_gmsh_model(name);
}

PatchResult patch_test(const TetMesh& lower, const TetMesh& upper, const std::string& method, const std::string& label);

PatchResult patch_test(int master_cells, int slave_cells, const std::string& method) {
  return patch_test(samples::make_box_mesh(master_cells, master_cells, 2, L, L, H),
                    samples::make_box_mesh(slave_cells, slave_cells, 2, L, L, H, {0, 0, H}), method,
                    "master " + std::to_string(master_cells) + " x " + std::to_string(master_cells) + " cells, slave " + std::to_string(slave_cells) +
                        " x " + std::to_string(slave_cells));
}

PatchResult patch_test(const TetMesh& lower, const TetMesh& upper, const std::string& method, const std::string& label) {
  testkit::TempDir dir;
  Scenario sc;
  sc.file = dir.path() / "patch.toml";
  sc.run.end_time = 0.2;
  sc.damping.alpha = 3000;
  sc.materials["m"] = testkit::linear_elastic_instance("m", 1e6, 0.3, 1000);
  sc.bodies.push_back(testkit::body_from_mesh(dir, "lower", lower, "m"));
  sc.bodies.push_back(testkit::body_from_mesh(dir, "upper", upper, "m"));
  sc.curves["ramp"] = CurveSpec{"ramp", {}, {}, true, 0.0, 0.01};
  sc.boundaries.push_back(testkit::boundary("lower", "zmin", solver::BoundaryType::fixed, {false, false, true}, "base"));
  for (const char* body : {"lower", "upper"}) {  // rollers on the two symmetry planes
    sc.boundaries.push_back(testkit::boundary(body, "xmin", solver::BoundaryType::fixed, {true, false, false}, std::string(body) + "_x"));
    sc.boundaries.push_back(testkit::boundary(body, "ymin", solver::BoundaryType::fixed, {false, true, false}, std::string(body) + "_y"));
  }
  BoundarySpec top = testkit::boundary("upper", "zmax", solver::BoundaryType::fixed, {false, false, true}, "top");
  top.type = BoundaryType::displacement, top.displacement = {0, 0, -2e-5}, top.curve = "ramp";  // 0.1 % strain
  sc.boundaries.push_back(top);
  ContactSpec c;
  c.slave_body = "upper", c.slave_surface = "zmin", c.master_body = "lower", c.master_surface = "zmax",
  c.method = method == "mortar" ? ContactMethod::mortar : ContactMethod::node_to_surface;
  sc.contacts.push_back(c);
  sc.contact_solver.tolerance = 1e-10;
  sc.contact_solver.max_iterations = 2000;
  const Model m = build_model(sc);
  ExplicitSolver s(m, sc.run, sc.damping);
  testkit::run_to_rest(s, 0.01, 1e-6);
  PatchResult r;
  r.kinetic_ratio = s.energies().kinetic / s.energies().internal;
  r.exact = std::abs(s.reactions().force[3 * (sc.boundaries.size() - 1) + 2]) / (L * L);
  const ContactRows& rows = s.contact().rows();
  r.lowest = 1e300, r.highest = -1e300;
  r.slave_nodes = s.contact().pairs()[0].slave_nodes.size();
  for (std::size_t k = 0; k < rows.size(); ++k) {
    r.worst_gap = std::min(r.worst_gap, rows.gap[k]);
    const double pk = (rows.reaction[3 * k] * rows.normal[3 * k] + rows.reaction[3 * k + 1] * rows.normal[3 * k + 1] +
                       rows.reaction[3 * k + 2] * rows.normal[3 * k + 2]) /
                      rows.area[k];
    r.lowest = std::min(r.lowest, pk), r.highest = std::max(r.highest, pk);
    ++r.nodes;
  }
  r.averaged = s.contact().averaged_peak_pressure(s.displacement().data(), 25e-6).value;
  std::printf(
      "%s, %s: %zu contact rows of %zu slave nodes, pressure %.2f .. %.2f Pa vs the top stress %.2f Pa (%+.3f %% .. %+.3f %%), "
      "largest 25 mm^2 average %.2f Pa (%+.3f %%), worst gap %.2e m, kinetic/strain %.1e\n",
      method.c_str(), label.c_str(), r.nodes, r.slave_nodes, r.lowest, r.highest, r.exact, 100 * (r.lowest / r.exact - 1),
      100 * (r.highest / r.exact - 1), r.averaged, 100 * (r.averaged / r.exact - 1), r.worst_gap, r.kinetic_ratio);
  return r;
}

// The blocked Uzawa sweep (contact_solver.sweep_blocks): a 30 x 30-cell block pressed and pushed
// sideways onto a 20 x 20-cell one with friction (961 mortar rows, each sharing master nodes with
// its neighbours), `steps` steps from touching.
struct SweepRun {
  std::vector<double> u, v;
  ContactStepReport last;
  int most_iterations = 0;
};

SweepRun press_and_slide(int sweep_blocks, int threads, int steps) {
  testkit::TempDir dir;
  Scenario sc;
  sc.file = dir.path() / "sweep.toml";
  sc.run.end_time = 1;
  sc.run.threads = threads;
  sc.materials["m"] = testkit::linear_elastic_instance("m", 1e6, 0.3, 1000);
  sc.bodies.push_back(testkit::body_from_mesh(dir, "lower", samples::make_box_mesh(20, 20, 2, L, L, H), "m"));
  sc.bodies.push_back(testkit::body_from_mesh(dir, "upper", samples::make_box_mesh(30, 30, 2, L, L, H, {0, 0, H}), "m"));
  sc.boundaries.push_back(testkit::boundary("lower", "zmin", solver::BoundaryType::fixed, {true, true, true}, "base"));
  BoundarySpec top = testkit::boundary("upper", "zmax", solver::BoundaryType::fixed, {true, true, true}, "top");
  top.type = BoundaryType::velocity, top.velocity = {0.02, 0, -0.05};
  sc.boundaries.push_back(top);
  ContactSpec c;
  c.slave_body = "upper", c.slave_surface = "zmin", c.master_body = "lower", c.master_surface = "zmax", c.method = ContactMethod::mortar,
  c.friction = 0.3;
  sc.contacts.push_back(c);
  sc.contact_solver.tolerance = 1e-10;
  sc.contact_solver.max_iterations = 2000;
  sc.contact_solver.sweep_blocks = sweep_blocks;
  const Model m = build_model(sc);
  ExplicitSolver s(m, sc.run, sc.damping);
  SweepRun r;
  for (int n = 0; n < steps; ++n) {
    s.advance_velocity();
    r.most_iterations = std::max(r.most_iterations, s.contact_report().iterations);
    s.advance_position();
  }
  s.advance_velocity();
  r.u = s.displacement(), r.v = s.velocity_at_step(), r.last = s.contact_report();
  return r;
}

}  // namespace

// The parallel Uzawa sweep (issue 15, speed): the rows cut into spatial blocks that share no node,
// each block swept in order on some thread, then the rows between blocks. Oracles: (1) the same
// bits on 1, 2 and 3 threads (the blocks do not depend on the thread count); (2) the sequential
// Gauss-Seidel sweep in row order (sweep_blocks = 1), to which it converges: both solve the same
// cone complementarity problem each step to the Uzawa tolerance 1e-10, so after 200 steps of
// frictional sliding the displacements and the contact force agree to 1e-6 relative.
TEST(Mortar, BlockedUzawaSweepMatchesTheSequentialOneOnAnyThreadCount) {
  const int steps = 200;
  const SweepRun sequential = press_and_slide(1, 1, steps), blocked = press_and_slide(16, 1, steps);
  const ContactStepReport& b = blocked.last;
  std::printf("blocked sweep: %d blocks, %zu of %zu rows between them, %zu active (%zu sticking, %zu slipping); most iterations %d (in order: %d)\n",
              b.sweep_blocks, b.rows_in_order, b.candidates, b.active, b.sticking, b.slipping, blocked.most_iterations, sequential.most_iterations);
  // At most one slab per 256 rows (961 rows: 3), each at least 2.5 rows' reaches thick (a row
  // reaches a slave and a master element, 0.67 + 1 mm, of 20 mm: 4 would fit).
  EXPECT_EQ(b.sweep_blocks, 3);
  EXPECT_GT(b.active, 900u);
  EXPECT_LT(b.rows_in_order, b.candidates / 4);
  double largest = 0, worst = 0;
  for (std::size_t i = 0; i < blocked.u.size(); ++i)
    largest = std::max(largest, std::abs(sequential.u[i])), worst = std::max(worst, std::abs(blocked.u[i] - sequential.u[i]));
  const double force_seq = norm(sequential.last.force), force_blocked = norm(b.force);
  std::printf("blocked vs in order after %d steps: largest displacement difference %.3e of %.3e m (%.2e); contact force %.9f vs %.9f N (%.2e)\n",
              steps, worst, largest, worst / largest, force_blocked, force_seq, force_blocked / force_seq - 1);
  EXPECT_LE(worst, 1e-6 * largest);
  EXPECT_NEAR(force_blocked, force_seq, 1e-6 * force_seq);
  for (int threads : {2, 3}) {
    const SweepRun other = press_and_slide(16, threads, steps);
    std::size_t differ = 0;
    for (std::size_t i = 0; i < other.u.size(); ++i) differ += std::memcmp(&other.u[i], &blocked.u[i], sizeof(double)) != 0;
    std::printf("%d threads: %zu of %zu displacement components differ in any bit from 1 thread's\n", threads, differ, other.u.size());
    EXPECT_EQ(differ, 0u);
    EXPECT_EQ(std::memcmp(other.v.data(), blocked.v.data(), other.v.size() * sizeof(double)), 0);
  }
}

TEST(Mortar, ContactPatchTestSlaveFinerAndSlaveCoarser) {
  for (const auto& [lower, upper] : {std::pair{6, 9}, std::pair{9, 6}}) {
    const PatchResult r = patch_test(lower, upper, "mortar");
    EXPECT_LE(r.kinetic_ratio, 1e-6);
    EXPECT_EQ(r.nodes, static_cast<std::size_t>((upper + 1) * (upper + 1)));
    EXPECT_NEAR(r.lowest, r.exact, 0.01 * r.exact);
    EXPECT_NEAR(r.highest, r.exact, 0.01 * r.exact);
    EXPECT_NEAR(r.averaged, r.exact, 0.01 * r.exact);  // a uniform field averages to itself
  }
  // For the record (not asserted): node-to-surface on the same meshes.
  patch_test(6, 9, "node_to_surface");
}

// The same on unstructured gmsh meshes of 2.5 mm and 1.7 mm (ratio 1.47), slave finer and slave
// coarser: the footprints' edges and corners coincide, but no boundary node of one mesh lies on a
// node of the other. Mortar: every node within 1 %. Node to surface: no slave node lost at the
// footprint's edges and corners (each has a row at rest; before, a corner node on the master's
// boundary edge was not found, sank in, and inverted an element), no row deeper than 1e-3 of an
// element.
TEST(Mortar, ContactPatchTestUnstructuredMeshesEqualFootprints) {
  const double coarse = 2.5e-3, fine = 1.7e-3;
  for (const auto& [h_lower, h_upper] : {std::pair{coarse, fine}, std::pair{fine, coarse}}) {
    const TetMesh lower = gmsh_box(0, h_lower, "lower"), upper = gmsh_box(H, h_upper, "upper");
    const std::string label =
        "gmsh " + std::to_string(h_lower * 1e3).substr(0, 3) + " mm below, " + std::to_string(h_upper * 1e3).substr(0, 3) + " mm above";
    const PatchResult m = patch_test(lower, upper, "mortar", label);
    EXPECT_LE(m.kinetic_ratio, 1e-6);
    EXPECT_EQ(m.nodes, m.slave_nodes);
    EXPECT_NEAR(m.lowest, m.exact, 0.01 * m.exact);
    EXPECT_NEAR(m.highest, m.exact, 0.01 * m.exact);
    EXPECT_NEAR(m.averaged, m.exact, 0.01 * m.exact);
    const PatchResult n = patch_test(lower, upper, "node_to_surface", label);
    EXPECT_LE(n.kinetic_ratio, 1e-6);
    EXPECT_GE(n.nodes, n.slave_nodes);  // every slave node found (a node in a corner may have two rows)
    EXPECT_GE(n.worst_gap, -1e-3 * std::min(h_lower, h_upper));
  }
}

// A slave triangle over a convex edge of the master, facing both faces (its normal within 60
// degrees of each): where its projections onto the two faces overlap, each of its points belongs
// to the face it is nearer to. Oracle: the weighted gaps G_j / D_j computed independently by a
// fine quadrature over the triangle (full coverage, so psi_j = 4 lambda_j - 1 and D_j = A / 3),
// with g the nearer face's signed height. Counting those points on both faces (as before) added
// the far face's depth: on the hand, a skin node lying on the block's face 1.9 mm from its edge got
// a gap of -0.3 mm, was pushed out at the recovery speed, and made the run's peak pressure.
TEST(Mortar, SlaveTriangleOverAConvexEdgeIsMeasuredAgainstTheNearerFace) {
  testkit::TempDir dir;
  const double a = 0.01;  // the block [0, a]^3: its top face z = a and side face x = a meet at the edge x = z = a
  TetMesh block = samples::make_box_mesh(2, 2, 2, a, a, a);
  testkit::add_whole_boundary_group(block);
  // One tet whose face P0 P1 P2 lies in the plane 0.6 x + 0.8 z = c (its normal within 60 degrees
  // of both faces' opposites): P0, P1 on the side face's plane 1.04 mm below the top, P2 1.96 mm
  // above the top; the part below the top is inside the block, at most 0.59 mm from a face.
  const double c = 13.17e-3;
  const Vec3 P0{a, 0.003, (c - 0.6 * a) / 0.8}, P1{a, 0.007, (c - 0.6 * a) / 0.8}, P2{0.006, 0.005, (c - 0.6 * 0.006) / 0.8};
  const Vec3 toward_block{-0.6, 0, -0.8};
  const Vec3 centroid = (1.0 / 3.0) * (P0 + P1 + P2);
  TetMesh tet;
  tet.nodes = {P0, P1, P2, centroid - 0.003 * toward_block};
  tet.tets = {{0, 1, 2, 3}};
  if (tet_volume(tet.nodes[0], tet.nodes[1], tet.nodes[2], tet.nodes[3]) < 0) tet.tets[0] = {1, 0, 2, 3};
  tet.tet_group = {1};
  std::array<int, 3> face{0, 1, 2};
  if (dot(cross(P1 - P0, P2 - P0), toward_block) < 0) face = {1, 0, 2};  // outward: towards the block
  tet.triangles = {face};
  tet.triangle_group = {2};
  tet.groups = {{3, 1, "tet"}, {2, 2, "face"}};
  Scenario sc;
  sc.file = dir.path() / "edge.toml";
  sc.materials["m"] = testkit::linear_elastic_instance("m", 1e6, 0.3, 1000);
  sc.bodies.push_back(testkit::body_from_mesh(dir, "block", block, "m"));
  sc.bodies.push_back(testkit::body_from_mesh(dir, "slave", tet, "m"));
  ContactSpec cs;
  cs.slave_body = "slave", cs.slave_surface = "face", cs.master_body = "block", cs.master_surface = "surface";
  cs.edge_pass = false;  // the mortar rows alone (the block's edge nodes would add rows of their own)
  sc.contacts.push_back(cs);
  const Model m = build_model(sc);
  ContactSolver contact(m);
  const std::vector<double> u(3 * m.num_nodes, 0.0), v_old(3 * m.num_nodes, 0.0);
  std::vector<double> v(3 * m.num_nodes, 0.0), inv_mass(3 * m.num_nodes);
  for (std::size_t i = 0; i < inv_mass.size(); ++i) inv_mass[i] = 1.0 / m.mass[i / 3];
  contact.correct_velocities(u.data(), v.data(), v_old.data(), inv_mass.data(), 1e-7, 1e-7, 1e-7);
  const ContactRows& rows = contact.rows();

  // The reference: midpoints of an n x n subdivision of the triangle.
  const int n = 600;
  const Vec3 P[3] = {P0, P1, P2};
  double G[3] = {0, 0, 0}, deepest_far_face = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; i + j < n; ++j)
      for (int up = 0; up < (i + j + 1 < n ? 2 : 1); ++up) {  // the n^2 small triangles, each by its centroid
        const double l1 = up ? (i + 2.0 / 3.0) / n : (i + 1.0 / 3.0) / n, l2 = up ? (j + 2.0 / 3.0) / n : (j + 1.0 / 3.0) / n;
        const double l[3] = {1 - l1 - l2, l1, l2};
        const Vec3 x = l[0] * P[0] + l[1] * P[1] + l[2] * P[2];
        const double h_top = x[2] - a, h_side = x[0] - a;  // over the top face everywhere; over the side face below the top
        const double g = (x[2] <= a && std::abs(h_side) < std::abs(h_top)) ? h_side : h_top;
        if (x[2] <= a) deepest_far_face = std::min(deepest_far_face, std::abs(h_side) < std::abs(h_top) ? h_top : h_side);
        for (int k = 0; k < 3; ++k) G[k] += (4 * l[k] - 1) * g / (static_cast<double>(n) * n);  // / A, times A below
      }
  double worst = 0, largest = 0;
  ASSERT_EQ(rows.size(), 3u);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const std::int32_t node = rows.slave(r);
    int k = 0;
    while (k < 3 && m.node_of_input[m.bodies[1].node_begin + static_cast<std::size_t>(k)] != node) ++k;
    ASSERT_LT(k, 3);
    const double reference = G[k] * 3;  // G_j / D_j with D_j = A / 3
    std::printf("slave vertex %d: weighted gap %+.4f mm, reference %+.4f mm\n", k, rows.gap[r] * 1e3, reference * 1e3);
    worst = std::max(worst, std::abs(rows.gap[r] - reference)), largest = std::max(largest, std::abs(reference));
  }
  std::printf("worst difference %.4f mm (%.2f %% of the largest gap %.4f mm); the far face's depth there reaches %.3f mm\n", worst * 1e3,
              100 * worst / largest, largest * 1e3, -deepest_far_face * 1e3);
  EXPECT_LE(worst, 0.01 * largest);
}
