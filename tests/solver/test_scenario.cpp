// solver/scenario: every malformed scenario gives one InputError naming the key and what was
// expected; the generated key reference matches docs/scenario-reference.md.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/internal_force.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/model_build.hpp"
#include "tactus/solver/run.hpp"
#include "tactus/solver/scenario.hpp"
#include "temp_dir.hpp"

using namespace tactus;
using namespace tactus::solver;

namespace {

const char* kValid = R"(
[run]
end_time = 1e-3
output_times = [5e-4, 1e-3]

[[bodies]]
name = "pad"
mesh = "pad.msh"
materials = { body = "skin" }
initial_velocity = [2.0, 0, 0]

[materials.skin]
type = "hgo"
c1 = 10206.9
k1 = 1.7
k2 = 882.847
k = 1.0e8
density = 1050.0
fibres = [[1, 1, 0], [1, -1, 0]]

[materials.bone]
type = "linear_elastic"
E = 10e9
nu = 0.22
density = 2150

[[boundary]]
body = "pad"
group = "xmin"
type = "fixed"
)";

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto pos = s.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  return s.replace(pos, from.size(), to);
}

class ScenarioFile : public ::testing::Test {
 protected:
  void SetUp() override { write_msh(dir / "pad.msh", samples::make_box_mesh(2, 2, 2, 0.01, 0.01, 0.01)); }
  std::filesystem::path write(const std::string& text) {
    std::ofstream(dir / "scenario.toml") << text;
    return dir / "scenario.toml";
  }
  // Expects InputError whose message contains every fragment.
  void expect_error(const std::string& text, std::initializer_list<std::string> fragments, bool build = false) {
    try {
      const Scenario sc = read_scenario(write(text));
      if (build) build_model(sc);
      FAIL() << "expected an InputError";
    } catch (const InputError& e) {
      for (const auto& f : fragments) EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what();
    }
  }
  testkit::TempDir dir;
};

}  // namespace

TEST_F(ScenarioFile, ValidScenarioReads) {
  const Scenario sc = read_scenario(write(kValid));
  EXPECT_DOUBLE_EQ(sc.run.end_time, 1e-3);
  EXPECT_DOUBLE_EQ(sc.run.time_step_safety, 0.9);
  ASSERT_EQ(sc.bodies.size(), 1u);
  EXPECT_EQ(sc.bodies[0].initial_velocity[0], 2.0);
  const Model m = build_model(sc);
  const auto& fib = m.blocks[0].material.constant_element_data();  // hgo's a_1, a_2
  EXPECT_NEAR(fib[0], std::sqrt(0.5), 1e-15);                      // normalised
  EXPECT_EQ(m.num_elements, 48u);
  std::size_t fixed = 0;
  for (auto c : m.constrained) fixed += c;
  EXPECT_EQ(fixed, 3u * 9u);  // the 3x3 nodes of the xmin face, all components
}

// Per-element fibres from a .vtu (cell data fibre_1, fibre_2) override the material's constant
// ones. Oracle: a file holding the constant directions gives exactly the forces of the constant
// fibres, even when the material declares other (here swapped) directions.
TEST_F(ScenarioFile, PerElementFibresFromFile) {
  const TetMesh mesh = read_msh(dir / "pad.msh");
  MeshField f1{"fibre_1", 3, {}}, f2{"fibre_2", 3, {}};
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    f1.values.insert(f1.values.end(), {2.0, 2.0, 0.0});  // normalised on reading
    f2.values.insert(f2.values.end(), {1.0, -1.0, 0.0});
  }
  write_vtu(dir / "fibres.vtu", mesh, {}, {f1, f2});
  Scenario constant = read_scenario(write(kValid));
  Scenario per_element = read_scenario(write(replace(replace(kValid, "fibres = [[1, 1, 0], [1, -1, 0]]", "fibres = [[1, -1, 0], [1, 1, 0]]"),
                                                     "initial_velocity = [2.0, 0, 0]", "initial_velocity = [2.0, 0, 0]\nfibres = \"fibres.vtu\"")));
  const Model a = build_model(constant), b = build_model(per_element);
  ASSERT_FALSE(a.blocks[0].per_element_data());
  ASSERT_TRUE(b.blocks[0].per_element_data());
  // Stretch along x so both fibre families are loaded.
  const std::size_t ndof = 3 * a.num_nodes;
  std::vector<double> u(ndof, 0.0);
  const std::vector<double> v(ndof, 0.0);
  std::vector<double> fa(ndof), fb(ndof);
  for (std::size_t i = 0; i < a.num_nodes; ++i) u[3 * i] = 0.08 * a.X[3 * i] + 0.02 * a.X[3 * i + 1];
  InternalForces(a, 0.0, 1).compute(u.data(), v.data(), fa.data());
  InternalForces(b, 0.0, 1).compute(u.data(), v.data(), fb.data());
  double diff = 0, norm = 0;
  for (std::size_t i = 0; i < u.size(); ++i) diff = std::max(diff, std::abs(fa[i] - fb[i])), norm = std::max(norm, std::abs(fa[i]));
  EXPECT_LE(diff, 1e-12 * norm);
  // And a file for another mesh is refused with the counts.
  write_vtu(dir / "other.vtu", samples::make_box_mesh(3, 2, 2, 0.01, 0.01, 0.01), {}, {});
  expect_error(replace(kValid, "initial_velocity = [2.0, 0, 0]", "initial_velocity = [2.0, 0, 0]\nfibres = \"other.vtu\""),
               {"other.vtu", "bodies[0].fibres", "27 nodes, 48 tets"}, true);
}

TEST_F(ScenarioFile, RailOfZeroLengthOrOnAPrescribedBody) {
  expect_error(replace(kValid, "mesh = \"pad.msh\"", "mesh = \"pad.msh\"\nrigid_guide = [0, 0, 0]"),
               {"bodies[0].rigid_guide", "non-zero length", "a zero vector"});
  expect_error(replace(kValid, "mesh = \"pad.msh\"", "mesh = \"pad.msh\"\nrigid_guide = [0, 0, 1]\nrigid_velocity = [0, 0, 0]"),
               {"bodies[0].rigid_guide", "a prescribed body"});
}
TEST_F(ScenarioFile, UnknownKey) { expect_error(replace(kValid, "end_time", "end_tme"), {"run.end_tme", "unknown key"}); }
TEST_F(ScenarioFile, MissingRequiredKey) { expect_error(replace(kValid, "k2 = 882.847\n", ""), {"materials.skin.k2", "missing"}); }
TEST_F(ScenarioFile, NegativeDensity) {
  expect_error(replace(kValid, "density = 2150", "density = -2150"), {"materials.bone.density", "> 0", "-2150"});
}
TEST_F(ScenarioFile, IncompressiblePoissonRatio) { expect_error(replace(kValid, "nu = 0.22", "nu = 0.5"), {"materials.bone.nu", "(-1, 0.5)"}); }
TEST_F(ScenarioFile, NonPositiveBulkModulus) { expect_error(replace(kValid, "k = 1.0e8", "k = 0"), {"materials.skin.k", "> 0"}); }
TEST_F(ScenarioFile, MaterialFormulationMustBeKnown) {
  expect_error(replace(kValid, "k2 = 882.847\n", "k2 = 882.847\nformulation = \"mixed\"\n"),
               {"materials.skin.formulation", "\"anp\" or \"standard\""});
}
TEST_F(ScenarioFile, PressureSmoothingMustBeASmallInteger) {
  expect_error(replace(kValid, "k2 = 882.847\n", "k2 = 882.847\npressure_smoothing = 1.5\n"),
               {"materials.skin.pressure_smoothing", "an integer", "1.5"});
  expect_error(replace(kValid, "k2 = 882.847\n", "k2 = 882.847\npressure_smoothing = 9\n"), {"materials.skin.pressure_smoothing", "[0, 8]", "9"});
}
TEST_F(ScenarioFile, UnknownMaterialType) {
  expect_error(replace(kValid, "\"linear_elastic\"", "\"mooney\""), {"materials.bone.type", "hgo", "mooney"});
}
TEST_F(ScenarioFile, HgoWithoutFibres) {
  expect_error(replace(kValid, "fibres = [[1, 1, 0], [1, -1, 0]]", ""), {"materials.skin.fibres", "element data for hgo"}, true);
}
TEST_F(ScenarioFile, BodyNamesUndefinedMaterial) {
  expect_error(replace(kValid, "body = \"skin\"", "body = \"skn\""), {"bodies[0].materials.body", "skn"});
}
TEST_F(ScenarioFile, GroupWithoutMaterial) {
  expect_error(replace(kValid, "body = \"skin\"", "tissue = \"skin\""), {"bodies[0].materials", "'body'", "found none"}, true);
}
TEST_F(ScenarioFile, MaterialForMissingGroup) {
  expect_error(replace(kValid, "body = \"skin\"", "\"*\" = \"skin\", tissue = \"bone\""), {"bodies[0].materials.tissue", "no such group"}, true);
}
TEST_F(ScenarioFile, BoundaryGroupNotInMesh) {
  expect_error(replace(kValid, "group = \"xmin\"", "group = \"palm\""), {"boundary[0].group", "palm", "xmin"}, true);
}
TEST_F(ScenarioFile, BoundaryWithGroupAndBox) {
  expect_error(replace(kValid, "type = \"fixed\"", "type = \"fixed\"\nbox = [[0,0,0],[1,1,1]]"), {"boundary[0]", "exactly one"});
}
// Loading keys (curves, displacement boundaries, pressure loads, rotation): each mistake is named.
TEST_F(ScenarioFile, CurveThatDoesNotExist) {
  expect_error(replace(kValid, "type = \"fixed\"", "type = \"velocity\"\nvelocity = [0, 0, 1]\ncurve = \"ramp\""),
               {"boundary[0].curve", "[curves.<name>]", "there is none", "ramp"});
}
TEST_F(ScenarioFile, CurveOnAFixedBoundary) {
  EXPECT_NO_THROW(read_scenario(write(std::string(kValid) + "[curves.ramp]\nsmooth_step = [0, 1e-3]\n")));  // valid so far
  expect_error(replace(kValid, "type = \"fixed\"", "type = \"fixed\"\ncurve = \"ramp\"") + "[curves.ramp]\nsmooth_step = [0, 1e-3]\n",
               {"boundary[0].curve", "velocity or displacement"});
}
TEST_F(ScenarioFile, CurveTimesMustIncrease) {
  expect_error(std::string(kValid) + "[curves.c]\ntimes = [0, 2e-3, 1e-3]\nvalues = [0, 1, 1]\n", {"curves.c.times", "strictly increasing"});
  expect_error(std::string(kValid) + "[curves.c]\ntimes = [0, 1e-3]\nvalues = [0]\n", {"curves.c", "same length", "2 times, 1 values"});
  expect_error(std::string(kValid) + "[curves.c]\nsmooth_step = [2e-3, 1e-3]\n", {"curves.c.smooth_step", "t1 > t0"});
}
TEST_F(ScenarioFile, DisplacementOnlyWithItsType) {
  expect_error(replace(kValid, "type = \"fixed\"", "type = \"fixed\"\ndisplacement = [0, 0, 1e-3]"),
               {"boundary[0].displacement", "type = \"displacement\""});
}
TEST_F(ScenarioFile, BoundaryNamesNameColumns) {
  expect_error(replace(kValid, "type = \"fixed\"", "type = \"fixed\"\nname = \"top face\""), {"boundary[0].name", "letters, digits", "top face"});
}
TEST_F(ScenarioFile, PressureOnAGroupThatIsNotThere) {
  expect_error(std::string(kValid) + "[[load]]\nbody = \"pad\"\ngroup = \"inner\"\ntype = \"pressure\"\npressure = 1e3\n",
               {"load[0].group", "physical surface group", "xmin", "inner"}, true);
}
TEST_F(ScenarioFile, RotationByMatrixMustBeARotation) {
  expect_error(
      replace(kValid, "initial_velocity = [2.0, 0, 0]", "initial_velocity = [2.0, 0, 0]\nrotate_matrix = [[1, 0, 0], [0, 1, 0], [0, 0, -1]]"),
      {"bodies[0].rotate_matrix", "determinant +1", "det -1"});
  expect_error(replace(kValid, "initial_velocity = [2.0, 0, 0]", "initial_velocity = [2.0, 0, 0]\nrotate_axis = [0, 0, 1]"),
               {"bodies[0].rotate_axis", "together"});
}
TEST_F(ScenarioFile, MissingMeshFile) { expect_error(replace(kValid, "pad.msh", "nowhere.msh"), {"nowhere.msh", "no such file"}, true); }
TEST_F(ScenarioFile, TomlSyntaxErrorGivesLine) { expect_error(replace(kValid, "end_time = 1e-3", "end_time = = 1e-3"), {"line 3", "valid TOML"}); }
TEST_F(ScenarioFile, OutputTimeAfterEnd) { expect_error(replace(kValid, "[5e-4, 1e-3]", "[5e-4, 2e-3]"), {"run.output_times", "run.end_time"}); }

// --set KEY=VALUE (tactus-solve, tactus-pipeline --study). Oracle: each override gives exactly
// the value a file holding it gives; a path the file does not have, an index past a list's end
// and a value of the wrong type are refused naming the override or the key.
TEST_F(ScenarioFile, OverridesReplaceValuesByPath) {
  const auto file = write(kValid);
  const Scenario sc =
      read_scenario(file, {}, {"run.end_time=2e-3", "bodies.0.initial_velocity=[1.5, 0, -0.5]", "run.time_step_safety=0.5", "materials.bone.E=5e9"});
  const Scenario edited = read_scenario(write(replace(replace(replace(kValid, "end_time = 1e-3", "end_time = 2e-3\ntime_step_safety = 0.5"),
                                                              "initial_velocity = [2.0, 0, 0]", "initial_velocity = [1.5, 0, -0.5]"),
                                                      "E = 10e9", "E = 5e9")));
  std::printf("--set: end_time %g (file %g), velocity %g %g %g, safety %g, bone E %g (file %g)\n", sc.run.end_time, edited.run.end_time,
              sc.bodies[0].initial_velocity[0], sc.bodies[0].initial_velocity[1], sc.bodies[0].initial_velocity[2], sc.run.time_step_safety,
              sc.materials.at("bone").values.numbers.at("E"), edited.materials.at("bone").values.numbers.at("E"));
  EXPECT_EQ(sc.run.end_time, edited.run.end_time);
  EXPECT_EQ(sc.bodies[0].initial_velocity, edited.bodies[0].initial_velocity);
  EXPECT_EQ(sc.run.time_step_safety, 0.5);  // a key the file leaves out is added
  EXPECT_EQ(sc.materials.at("bone").values.numbers.at("E"), 5e9);
  EXPECT_EQ(sc.overrides.size(), 4u);
  auto refused = [&](const std::string& item, std::initializer_list<std::string> fragments) {
    try {
      read_scenario(write(kValid), {}, {item});
      ADD_FAILURE() << item << ": expected an InputError";
    } catch (const InputError& e) {
      for (const auto& f : fragments) EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what();
    }
  };
  refused("bodies.3.mesh=x.msh", {"--set bodies.3.mesh", "an index from 0 to 0 into bodies"});
  refused("nosuch.key=1", {"--set nosuch.key", "no nosuch in the file"});
  refused("run.end_time", {"--set run.end_time", "KEY=VALUE"});
  refused("run.end_time=soon", {"run.end_time", "number"});  // a bare word is a string: the reader names the key
  refused("run.end_time.x=1", {"run.end_time is a value"});
}

// The committed reference must be what the declarations generate (regenerate with
// `tactus-solve keys > docs/scenario-reference.md`).
TEST(ScenarioReference, DocsMatchDeclarations) {
  std::ifstream in(std::string(TACTUS_SOURCE_DIR) + "/docs/scenario-reference.md");
  ASSERT_TRUE(in.good());
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), scenario_reference_markdown());
}

namespace {
// Two boxes 1 cm apart in z: the pad (0..1 cm) and a tool (1.05..2.05 cm) above it.
std::string contact_scenario(double tool_z, const std::string& contact_keys) {
  std::ostringstream o;
  o << kValid << R"(
[[bodies]]
name = "tool"
mesh = "pad.msh"
materials = { "*" = "bone" }
translate = [0, 0, )"
    << tool_z << R"(]

[[contact]]
slave_body = "pad"
slave_surface = "zmax"
master_body = "tool"
)" << contact_keys
    << "\n";
  return o.str();
}
}  // namespace

TEST_F(ScenarioFile, ContactPairReads) {
  const Scenario sc = read_scenario(write(contact_scenario(0.0105, "master_surface = \"zmin\"\nfriction = 0.3\ntwo_pass = true")));
  ASSERT_EQ(sc.contacts.size(), 1u);
  EXPECT_DOUBLE_EQ(sc.contacts[0].friction, 0.3);
  const Model m = build_model(sc);
  ASSERT_EQ(m.contact_pairs.size(), 2u);  // two passes
  EXPECT_EQ(m.contact_pairs[0].slave_nodes.size(), 9u);
  EXPECT_EQ(m.contact_pairs[0].master->triangles().size(), 3u * 8u);
  double area = 0;
  for (double a : m.contact_pairs[0].slave_area) area += a;
  EXPECT_NEAR(area, 1e-4, 1e-15);  // the 1 cm x 1 cm face
  // The second pass's slaves are on the other body: it counts reversed; both are one entry's.
  EXPECT_EQ(m.contact_pairs[0].report_sign, 1.0);
  EXPECT_EQ(m.contact_pairs[1].report_sign, -1.0);
  EXPECT_EQ(m.contact_pairs[0].entry, m.contact_pairs[1].entry);
  // Master normals point out of the tool (its zmin face: -z).
  const auto& t = m.contact_pairs[0].master->triangles();
  const double *a = &m.X[3 * t[0]], *b = &m.X[3 * t[1]], *c = &m.X[3 * t[2]];
  const double nz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
  EXPECT_LT(nz, 0.0);
}
TEST_F(ScenarioFile, ContactMissingSurface) {
  expect_error(contact_scenario(0.0105, "master_surface = \"top\""), {"contact[0].master_surface", "surface group of body 'tool'", "zmin", "\"top\""},
               true);
}
TEST_F(ScenarioFile, ContactNegativeFriction) {
  expect_error(contact_scenario(0.0105, "master_surface = \"zmin\"\nfriction = -0.1"), {"contact[0].friction", ">= 0", "-0.1"});
}
TEST_F(ScenarioFile, ContactUnknownBody) {
  expect_error(replace(contact_scenario(0.0105, "master_surface = \"zmin\""), "master_body = \"tool\"", "master_body = \"block\""),
               {"contact[0].master_body", "\"block\""});
}
// Bodies overlapping by 0.3 mm at t = 0 are refused with the depth, not pushed apart.
TEST_F(ScenarioFile, ContactOverlapAtStartIsReported) {
  const Scenario sc = read_scenario(write(contact_scenario(0.0097, "master_surface = \"zmin\"")));
  const Model m = build_model(sc);
  try {
    ExplicitSolver solver(m, sc.run, sc.damping);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("contact[0]"), std::string::npos) << msg;
    EXPECT_NE(msg.find("0.3 mm inside"), std::string::npos) << msg;
    EXPECT_NE(msg.find("body 'pad'"), std::string::npos) << msg;
  }
}

// Silently accepted before: a surface in contact with itself (no self-contact exists yet).
// A surface against itself is self-contact (node to surface, one pass): mortar and two_pass are refused.
TEST_F(ScenarioFile, SelfContactWithMortarOrTwoPassIsRefused) {
  auto self = [&](const std::string& keys) {
    return replace(contact_scenario(0.0105, "master_surface = \"zmax\"\n" + keys), "master_body = \"tool\"", "master_body = \"pad\"");
  };
  expect_error(self("method = \"mortar\""), {"contact[0].method", "self-contact", "\"pad/zmax\" against itself"});
  expect_error(self("two_pass = true"), {"contact[0].two_pass", "self-contact"});
}

// The default method: mortar between two bodies in one pass, node to surface for self-contact and
// two_pass (a rigid plane has its own master); mortar with two_pass is refused.
TEST_F(ScenarioFile, ContactMethodDefaults) {
  const Model one = build_model(read_scenario(write(contact_scenario(0.0105, "master_surface = \"zmin\""))));
  ASSERT_EQ(one.contact_pairs.size(), 1u);
  EXPECT_EQ(one.contact_pairs[0].master->describe().rfind("mortar surface", 0), 0u) << one.contact_pairs[0].master->describe();
  const Model two = build_model(read_scenario(write(contact_scenario(0.0105, "master_surface = \"zmin\"\ntwo_pass = true"))));
  ASSERT_EQ(two.contact_pairs.size(), 2u);
  EXPECT_EQ(two.contact_pairs[0].master->describe().rfind("deformable surface", 0), 0u) << two.contact_pairs[0].master->describe();
  const Model chosen = build_model(read_scenario(write(contact_scenario(0.0105, "master_surface = \"zmin\"\nmethod = \"node_to_surface\""))));
  EXPECT_EQ(chosen.contact_pairs[0].master->describe().rfind("deformable surface", 0), 0u) << chosen.contact_pairs[0].master->describe();
  expect_error(contact_scenario(0.0105, "master_surface = \"zmin\"\ntwo_pass = true\nmethod = \"mortar\""), {"contact[0].two_pass", "mortar"});
  // The edge pass is mortar's (one face of a block has no edge between two of its faces: one pair above).
  expect_error(contact_scenario(0.0105, "master_surface = \"zmin\"\nmethod = \"node_to_surface\"\nedge_pass = true"),
               {"contact[0].edge_pass", "only with mortar", "node_to_surface"});
  EXPECT_NO_THROW(read_scenario(write(contact_scenario(0.0105, "master_surface = \"zmin\"\nmethod = \"node_to_surface\"\nedge_pass = false"))));
}

// Silently accepted before: a duplicated node used by tets (a crack in the mesh).
TEST_F(ScenarioFile, CrackedMeshIsRefused) {
  TetMesh m = samples::make_box_mesh(2, 2, 2, 0.01, 0.01, 0.01);
  // Give one tet its own copy of a node it shares with its neighbours.
  const int shared = m.tets[0][0];
  m.nodes.push_back(m.nodes[static_cast<std::size_t>(shared)]);
  m.tets[0][0] = static_cast<int>(m.nodes.size()) - 1;
  write_msh(dir / "pad.msh", m);
  expect_error(kValid, {"pad.msh", "a crack", "conforming"}, true);
}

// Runaway guards: counted and refused before anything is built.
TEST_F(ScenarioFile, RunawayOutputScheduleIsRefused) {
  expect_error(replace(replace(kValid, "end_time = 1e-3", "end_time = 1000"), "output_times = [5e-4, 1e-3]", "output_interval = 1e-9"),
               {"run.output_interval", "run.max_outputs", "1e+12 states"});
  expect_error(replace(kValid, "output_times = [5e-4, 1e-3]", "output_interval = 1e-300"), {"run.output_interval", "run.max_outputs"});
}

// The committed results reference must be what the file contracts generate (regenerate with
// `tactus-solve results-reference > docs/results-reference.md` and `... --json >
// docs/results-reference.json`; the Python scripts read the JSON).
TEST(ResultsReference, DocsMatchContracts) {
  const std::string docs = std::string(TACTUS_SOURCE_DIR) + "/docs/";
  std::ifstream md(docs + "results-reference.md"), js(docs + "results-reference.json");
  ASSERT_TRUE(md.good() && js.good());
  std::stringstream text;
  text << md.rdbuf();
  EXPECT_EQ(text.str(), results_reference_markdown());
  EXPECT_EQ(nlohmann::json::parse(js), results_reference_json());
}

// Every integer key and every enumeration key, found from the declarations themselves (so a new
// key is covered without a new test): 2.5 for an integer and "no_such_value" for an enumeration
// are refused naming the key (run.threads = 2.5 once ran on 2 threads). Oracle: the key's full
// path and "an integer" / its first valid value in the message.
TEST_F(ScenarioFile, EveryIntegerAndEnumerationKeyRefusesABadValue) {
  // A scenario with one table of every section, and where each section's keys go.
  const std::string base = std::string(kValid) + R"(
[damping]
alpha = 1.0
[[bodies]]
name = "tool"
mesh = "pad.msh"
materials = { "*" = "bone" }
translate = [0, 0, 0.0105]
[curves.ramp]
times = [0, 1e-3]
values = [0, 1]
[[load]]
body = "pad"
group = "xmax"
type = "pressure"
pressure = 10.0
[[contact]]
slave_body = "tool"
slave_surface = "zmin"
master_body = "pad"
master_surface = "zmax"
[contact_solver]
tolerance = 1e-6
[[pipeline.meshes]]
output = "pad.msh"
kind = "box"
)";
  ASSERT_NO_THROW(read_scenario(write(base)));
  // The line after which a key of each section is inserted (materials: the hgo law's section).
  const std::map<std::string, std::string> anchor{{"run", "end_time = 1e-3\n"},
                                                  {"damping", "alpha = 1.0\n"},
                                                  {"bodies", "initial_velocity = [2.0, 0, 0]\n"},
                                                  {"curves.<name>", "values = [0, 1]\n"},
                                                  {"boundary", "type = \"fixed\"\n"},
                                                  {"load", "pressure = 10.0\n"},
                                                  {"contact", "master_surface = \"zmax\"\n"},
                                                  {"contact_solver", "tolerance = 1e-6\n"},
                                                  {"pipeline.meshes", "kind = \"box\"\n"},
                                                  {"materials.<name> with type = \"hgo\"", "k2 = 882.847\n"}};
  std::size_t integers = 0, enumerations = 0;
  for (const SectionSpec& section : scenario_reference()) {
    for (const ValueSpec& key : section.keys) {
      const bool integer = key.type == ValueType::integer, enumeration = !key.choices.empty();
      if (!integer && !enumeration) continue;
      if (section.name.rfind("materials.<name> with type", 0) == 0 && section.name != "materials.<name> with type = \"hgo\"") {
        // Keys every law with a volumetric split shares are tried on hgo; a law's own key needs a
        // material of that law here.
        bool shared = false;
        for (const SectionSpec& s : scenario_reference())
          if (s.name == "materials.<name> with type = \"hgo\"") shared = s.find(key.key) != nullptr;
        ASSERT_TRUE(shared) << section.name << "." << key.key << ": add a material of this law to the test scenario";
        continue;
      }
      const auto where = anchor.find(section.name);
      ASSERT_NE(where, anchor.end()) << "no table of section " << section.name << " in the test scenario (key " << key.key << ")";
      std::string path = section.name;
      if (section.name == "materials.<name> with type = \"hgo\"") path = "materials.skin";
      if (section.name == "curves.<name>") path = "curves.ramp";
      if (section.name == "bodies" || section.name == "boundary" || section.name == "load" || section.name == "contact" ||
          section.name == "pipeline.meshes")
        path += "[0]";
      if (section.name == "bodies") path = "bodies[0]";
      // An already present key is replaced (type, kind), else the key is added after the anchor.
      std::string text = base;
      const std::string bad = integer ? "2.5" : "\"no_such_value\"";
      const std::size_t at = text.find(where->second);
      ASSERT_NE(at, std::string::npos);
      const std::string line = key.key + " = ";
      const std::size_t table_start = text.rfind("\n[", at), section_end = text.find("\n[", at);
      const std::size_t own = text.find("\n" + line, table_start);
      if (own != std::string::npos && own < section_end) {
        const std::size_t eol = text.find('\n', own + 1);
        text.replace(own + 1, eol - own - 1, line + bad);
      } else {
        text.insert(at + where->second.size(), line + bad + "\n");
      }
      std::string message;
      try {
        read_scenario(write(text));
      } catch (const InputError& e) {
        message = e.what();
      }
      std::printf("%-28s %-22s -> %s\n", path.c_str(), key.key.c_str(), message.c_str());
      EXPECT_NE(message.find(path + "." + key.key), std::string::npos) << message;
      EXPECT_NE(message.find(integer ? "an integer" : "\"" + key.choices.front() + "\""), std::string::npos) << message;
      (integer ? integers : enumerations) += 1;
    }
  }
  std::printf("%zu integer keys and %zu enumeration keys refused a bad value\n", integers, enumerations);
  EXPECT_GE(integers, 6u);      // threads, history_every, max_outputs, max_steps, max_iterations, sweep_blocks, pressure_smoothing
  EXPECT_GE(enumerations, 6u);  // step_estimate, boundary type, load type, contact method, mesh kind, formulation
}

// A run shorter than half a step is blamed on run.end_time, in the scenario's own file (it once
// named run.output_times in a file called "scenario").
TEST_F(ScenarioFile, RunShorterThanHalfAStepNamesTheEndTime) {
  const Scenario sc = read_scenario(write(replace(replace(kValid, "end_time = 1e-3", "end_time = 1e-9"), "output_times = [5e-4, 1e-3]", "")));
  const Model m = build_model(sc);
  std::string message;
  try {
    ExplicitSolver solver(m, sc.run, sc.damping);
  } catch (const InputError& e) {
    message = e.what();
  }
  std::printf("%s\n", message.c_str());
  EXPECT_NE(message.find("scenario.toml: run.end_time"), std::string::npos) << message;
  EXPECT_NE(message.find("half a time step"), std::string::npos) << message;
}
