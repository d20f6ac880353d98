// core/mesh: .msh (gmsh API) and .vtu round trips preserve every value; gmsh-independent readers
// (meshio) see the same counts and groups; bad files give InputError naming the problem.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>

#include "expect_error.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/mesh.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "temp_dir.hpp"

using namespace tactus;
using tactus::testkit::expect_input_error;
using tactus::testkit::TempDir;

namespace {

// A two-material mesh: the box's upper half becomes group 2 "bone".
TetMesh two_material_box() {
  TetMesh m = tactus::samples::make_box_mesh(4, 3, 2, 0.04, 0.03, 0.02, {0.001, -0.002, 0.0003});
  tactus::samples::perturb_interior_nodes(m, 0.01, 0.2, 11);  // non-round coordinates
  m.groups.push_back({3, 2, "bone"});
  for (std::size_t e = 0; e < m.tets.size(); ++e) {
    double z = 0;
    for (int v : m.tets[e]) z += m.nodes[v][2] / 4;
    if (z > 0.0103) m.tet_group[e] = 2;
  }
  return m;
}

// ulp_tolerance 0: bit-exact; gmsh's ASCII writer prints 16 significant digits, which can be
// 1 ulp off an IEEE double, so the ASCII test allows 2 ulp (relative 4.5e-16).
void expect_same_mesh(const TetMesh& a, const TetMesh& b, bool with_triangles, double ulp_tolerance = 0) {
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  for (std::size_t i = 0; i < a.nodes.size(); ++i)
    for (int c = 0; c < 3; ++c)
      EXPECT_LE(std::abs(a.nodes[i][c] - b.nodes[i][c]), ulp_tolerance * std::numeric_limits<double>::epsilon() * std::abs(a.nodes[i][c]))
          << "node " << i;
  // Elements may come back grouped by physical group: compare as multisets of (group, nodes).
  auto tets = [](const TetMesh& m) {
    std::multiset<std::pair<int, std::array<int, 4>>> s;
    for (std::size_t e = 0; e < m.tets.size(); ++e) s.insert({m.tet_group[e], m.tets[e]});
    return s;
  };
  EXPECT_EQ(tets(a), tets(b));
  if (!with_triangles) return;
  auto tris = [](const TetMesh& m) {
    std::multiset<std::pair<int, std::array<int, 3>>> s;
    for (std::size_t e = 0; e < m.triangles.size(); ++e) s.insert({m.triangle_group[e], m.triangles[e]});
    return s;
  };
  EXPECT_EQ(tris(a), tris(b));
  ASSERT_EQ(a.groups.size(), b.groups.size());
  for (const auto& g : a.groups) {
    const auto* h = b.find_group(g.dim, g.name);
    ASSERT_NE(h, nullptr) << g.name;
    EXPECT_EQ(h->tag, g.tag);
  }
}

}  // namespace

// Oracle: the mesh written. Binary (tactus' default) stores raw doubles: bit-exact.
TEST(MeshMsh, BinaryRoundTripPreservesEveryValue) {
  TempDir dir;
  const TetMesh m = two_material_box();
  write_msh(dir / "m.msh", m);
  expect_same_mesh(m, read_msh(dir / "m.msh"), true);
}

TEST(MeshMsh, AsciiRoundTripWithinTwoUlp) {
  TempDir dir;
  const TetMesh m = two_material_box();
  write_msh(dir / "m.msh", m, false);
  expect_same_mesh(m, read_msh(dir / "m.msh"), true, 2.0);
}

TEST(MeshMsh, FileIsMsh41) {
  TempDir dir;
  write_msh(dir / "m.msh", two_material_box(), false);
  std::ifstream in(dir / "m.msh");
  std::string l1, l2;
  std::getline(in, l1);
  std::getline(in, l2);
  EXPECT_EQ(l1, "$MeshFormat");
  EXPECT_EQ(l2.substr(0, 6), "4.1 0 ");
}

// Independent reader: meshio (python3-meshio) must see the same counts and physical names.
// A state's time, units and tensor component names where ParaView looks for them. Oracle: VTK's
// own Python reader (tests/core/vtu_field_data.py) finds TimeValue, "units" and the stress's
// xx .. xz names, and tactus's reader gets the time back exactly; a file written without a time
// has none.
TEST(MeshVtu, TimeUnitsAndComponentNamesAsParaViewReadsThem) {
  TempDir dir;
  const TetMesh m = two_material_box();
  MeshField stress{"cauchy_stress", 6, std::vector<double>(6 * m.tets.size(), 1.0), {"xx", "yy", "zz", "xy", "yz", "xz"}};
  write_vtu(dir / "s.vtu", m, {}, {stress}, nullptr, 2.5e-3);
  write_vtu(dir / "plain.vtu", m);
  EXPECT_EQ(read_vtu(dir / "s.vtu").time, 2.5e-3);
  EXPECT_FALSE(read_vtu(dir / "plain.vtu").time.has_value());
  const std::string script = std::string(TACTUS_SOURCE_DIR) + "/tests/core/vtu_field_data.py";
  const std::string out = (dir / "facts.txt").string();
  ASSERT_EQ(std::system(("/usr/bin/python3 " + script + " " + (dir / "s.vtu").string() + " > " + out).c_str()), 0);
  std::ifstream in(out);
  std::string facts((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::printf("VTK's reader finds:\n%s", facts.c_str());
  EXPECT_NE(facts.find("TimeValue 0.0025\n"), std::string::npos);
  EXPECT_NE(facts.find("units SI (m, kg, s, Pa, J)\n"), std::string::npos);
  EXPECT_NE(facts.find("component cauchy_stress 0 xx\n"), std::string::npos);
  EXPECT_NE(facts.find("component cauchy_stress 5 xz\n"), std::string::npos);
}

TEST(MeshMsh, ReadByMeshioWithSameCountsAndGroups) {
  TempDir dir;
  const TetMesh m = two_material_box();
  write_msh(dir / "m.msh", m);
  const std::string script = std::string(TACTUS_SOURCE_DIR) + "/tests/core/msh_summary.py";
  const std::string out = (dir / "summary.txt").string();
  ASSERT_EQ(std::system(("/usr/bin/python3 " + script + " " + (dir / "m.msh").string() + " > " + out).c_str()), 0);
  std::ifstream in(out);
  std::map<std::string, long> summary;
  std::string key;
  long value;
  while (in >> key >> value) summary[key] = value;
  EXPECT_EQ(summary["points"], static_cast<long>(m.nodes.size()));
  EXPECT_EQ(summary["tetra"], static_cast<long>(m.tets.size()));
  EXPECT_EQ(summary["triangle"], static_cast<long>(m.triangles.size()));
  for (const auto& g : m.groups) EXPECT_EQ(summary["group:" + g.name], g.dim) << g.name;
  long bone = 0;
  for (int g : m.tet_group) bone += g == 2;
  EXPECT_EQ(summary["cells_in:bone"], bone);
}

TEST(MeshVtu, RoundTripPreservesEveryValue) {
  TempDir dir;
  const TetMesh m = two_material_box();
  MeshField disp{"displacement", 3, {}}, vm{"von_mises", 1, {}};
  for (std::size_t i = 0; i < m.nodes.size(); ++i)
    for (int c = 0; c < 3; ++c) disp.values.push_back(1e-3 * std::sin(static_cast<double>(3 * i + c)));
  for (std::size_t e = 0; e < m.tets.size(); ++e) vm.values.push_back(1e5 / (1.0 + static_cast<double>(e)));
  write_vtu(dir / "m.vtu", m, {disp}, {vm});
  const VtuContents back = read_vtu(dir / "m.vtu");
  expect_same_mesh(m, back.mesh, false);
  ASSERT_NE(back.point_field("displacement"), nullptr);
  ASSERT_NE(back.cell_field("von_mises"), nullptr);
  EXPECT_EQ(back.point_field("displacement")->values, disp.values);
  EXPECT_EQ(back.cell_field("von_mises")->values, vm.values);
}

TEST(MeshErrors, MissingMsh) {
  TempDir dir;
  expect_input_error([&] { read_msh(dir / "none.msh"); }, {"none.msh", "no such file"});
}

TEST(MeshErrors, GarbageMsh) {
  TempDir dir;
  std::ofstream(dir / "g.msh") << "hello\nworld\n";
  expect_input_error([&] { read_msh(dir / "g.msh"); }, {"g.msh"});
}

TEST(MeshErrors, TruncatedMsh) {
  TempDir dir;
  write_msh(dir / "t.msh", two_material_box());
  tactus::testkit::truncate_file(dir / "t.msh", std::filesystem::file_size(dir / "t.msh") / 2);
  expect_input_error([&] { read_msh(dir / "t.msh"); }, {"t.msh"});
}

TEST(MeshErrors, MshWithoutPhysicalVolumes) {
  TempDir dir;
  std::ofstream(dir / "np.msh") << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                                   "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n"
                                   "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n";
  expect_input_error([&] { read_msh(dir / "np.msh"); }, {"np.msh", "physical volume"});
}

TEST(MeshErrors, GarbageVtu) {
  TempDir dir;
  std::ofstream(dir / "g.vtu") << "<VTKFile broken";
  expect_input_error([&] { read_vtu(dir / "g.vtu"); }, {"g.vtu"});
}

TEST(MeshErrors, ValidateNamesBadNodeIndex) {
  TetMesh m = two_material_box();
  m.tets[5][2] = static_cast<int>(m.nodes.size()) + 3;
  expect_input_error([&] { m.validate("in-memory"); }, {"tet 6", "node indices"});
}

// ---------------------------------------------------------------------------------------------
// tactus's own MSH reader against libgmsh's (an independent implementation), on the four
// encodings: 4.1 binary and ASCII (tactus writes these), 2.2 ASCII and binary (older tools).
#include <gmsh.h>

#include "tactus/core/gmsh_session.hpp"

namespace {

TetMesh read_with_gmsh(const std::filesystem::path& file) {
  GmshSession session;
  gmsh::open(file.string());
  return tet_mesh_from_gmsh_model(file.string());
}

void resave_with_gmsh(const std::filesystem::path& in, const std::filesystem::path& out, double version, bool binary) {
  GmshSession session;
  gmsh::open(in.string());
  gmsh::option::setNumber("Mesh.MshFileVersion", version);
  gmsh::option::setNumber("Mesh.Binary", binary ? 1 : 0);
  gmsh::option::setNumber("Mesh.SaveAll", 0);
  gmsh::write(out.string());
}

std::string file_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_text(const std::filesystem::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }

}  // namespace

TEST(MeshMsh, OwnReaderAgreesWithGmshOnEveryEncoding) {
  TempDir dir;
  TetMesh m = two_material_box();
  m.groups.push_back({2, 7, "top"});
  for (std::size_t t = 0; t < 4; ++t) m.triangles.push_back({m.tets[t][0], m.tets[t][1], m.tets[t][2]}), m.triangle_group.push_back(7);
  write_msh(dir / "b41.msh", m, true);
  write_msh(dir / "a41.msh", m, false);
  resave_with_gmsh(dir / "b41.msh", dir / "a22.msh", 2.2, false);
  resave_with_gmsh(dir / "b41.msh", dir / "b22.msh", 2.2, true);
  // Elements as coordinates, so node numbering (libgmsh renumbers 2.2 files) does not matter.
  auto by_coordinates = [](const TetMesh& mesh) {
    std::multiset<std::pair<int, std::vector<double>>> tets, tris;
    for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
      std::vector<double> x;
      for (int v : mesh.tets[e]) x.insert(x.end(), mesh.nodes[v].begin(), mesh.nodes[v].end());
      tets.insert({mesh.tet_group[e], x});
    }
    for (std::size_t e = 0; e < mesh.triangles.size(); ++e) {
      std::vector<double> x;
      for (int v : mesh.triangles[e]) x.insert(x.end(), mesh.nodes[v].begin(), mesh.nodes[v].end());
      tris.insert({mesh.triangle_group[e], x});
    }
    return std::pair{tets, tris};
  };
  for (const char* name : {"b41.msh", "a41.msh", "a22.msh", "b22.msh"}) {
    SCOPED_TRACE(name);
    const TetMesh ours = read_msh(dir / name), theirs = read_with_gmsh(dir / name);
    EXPECT_TRUE(by_coordinates(ours) == by_coordinates(theirs));
    ASSERT_EQ(ours.groups.size(), theirs.groups.size());
    for (const auto& g : theirs.groups) EXPECT_NE(ours.find_group(g.dim, g.name), nullptr) << g.name;
    if (std::string(name).find("41") != std::string::npos) {
      EXPECT_EQ(ours.tets, theirs.tets);  // same numbering and order
    }
    std::printf("%s: %zu nodes, %zu tets, %zu triangles: identical to libgmsh's reading\n", name, ours.nodes.size(), ours.tets.size(),
                ours.triangles.size());
  }
}

// The corruptions that crashed libgmsh's reader (a bad-input probe): each is now one InputError
// naming the file and the place.
TEST(MeshErrors, CorruptMshIsRefusedWhereLibgmshCrashed) {
  TempDir dir;
  write_msh(dir / "b.msh", two_material_box(), true);
  write_msh(dir / "a.msh", two_material_box(), false);
  const std::string bin = file_text(dir / "b.msh"), ascii = file_text(dir / "a.msh");
  auto expect_refused = [&](const std::string& bytes, std::initializer_list<std::string> fragments) {
    write_text(dir / "c.msh", bytes);
    expect_input_error([&] { read_msh(dir / "c.msh"); }, fragments);
  };
  // Bytes inserted into binary $Elements.
  std::string s = bin;
  s.insert(s.find("$Elements") + 40, "\x07\x07\x07\x07\x07");
  expect_refused(s, {"c.msh", "$Elements"});
  // A run deleted from $Nodes.
  s = bin;
  s.erase(s.find("$Nodes") + 100, 57);
  expect_refused(s, {"c.msh"});
  // An element block of 99999999999 elements (ASCII).
  s = ascii;
  {
    const auto at = s.find("$Elements\n") + 10;
    const auto line2 = s.find('\n', s.find('\n', at) + 1);  // the first block header line
    const auto start = s.find('\n', at) + 1;
    std::string header = s.substr(start, line2 - start);
    header = header.substr(0, header.rfind(' ')) + " 99999999999";
    s.replace(start, line2 - start, header);
  }
  expect_refused(s, {"c.msh", "$Elements"});
  // A physical dimension of -2147483649.
  s = ascii;
  s.replace(s.find("$PhysicalNames\n") + 15 + 2, 1, "-2147483649");
  expect_refused(s, {"c.msh", "$PhysicalNames"});
  // A duplicated count line.
  s = ascii;
  {
    const auto at = s.find("$Nodes\n") + 7;
    const auto end = s.find('\n', at) + 1;
    s.insert(end, s.substr(at, end - at));
  }
  expect_refused(s, {"c.msh", "$Nodes"});
  // A negative entity tag.
  s = ascii;
  {
    const auto at = s.find("$Entities\n") + 10;
    const auto line = s.find('\n', at) + 1;  // first entity line
    s.insert(line, "-");
  }
  expect_refused(s, {"c.msh", "$Entities"});
}

// A tet referring to a node that does not exist, and a coordinate of 1e30 (a step of 3e-38 s).
TEST(MeshErrors, MshReferencesAndCoordinatesAreChecked) {
  TempDir dir;
  const std::string head =
      "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n3 1 \"v\"\n$EndPhysicalNames\n"
      "$Entities\n0 0 0 1\n1 0 0 0 1 1 1 1 1 0\n$EndEntities\n";
  std::ofstream(dir / "r.msh") << head << "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n"
                               << "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 9\n$EndElements\n";
  expect_input_error([&] { read_msh(dir / "r.msh"); }, {"r.msh", "node tags defined in $Nodes", "tag 9"});
  std::ofstream(dir / "x.msh") << head << "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1e30 0 0\n0 1 0\n0 0 1\n$EndNodes\n"
                               << "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n";
  expect_input_error([&] { read_msh(dir / "x.msh"); }, {"x.msh", "coordinates within 1e9"});
  std::ofstream(dir / "ok.msh") << head << "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n"
                                << "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n";
  EXPECT_EQ(read_msh(dir / "ok.msh").tets.size(), 1u);
}
