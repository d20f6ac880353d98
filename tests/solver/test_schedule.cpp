// solver/schedule: every requested state is written once, at exactly its time, and no step is
// below half the nominal one (the end-time bug: 2,000 additions of 1e-4 reached
// 0.1999999999999943, a last step of 5.7e-15 s followed, and the state at 0.2 s was never written).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <regex>
#include <sstream>

#include "expect_error.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/reference.hpp"
#include "tactus/solver/run.hpp"
#include "tactus/solver/schedule.hpp"
#include "temp_dir.hpp"

using namespace tactus;
using namespace tactus::solver;

namespace {

// The benchmark cube, coarse: neo-Hookean, bottom fixed, top pressed at 0.05 m/s, alpha 50/s.
Scenario cube(const std::filesystem::path& dir, double end_time, double time_step) {
  write_msh(dir / "cube.msh", samples::make_box_mesh(4, 4, 4, 0.1, 0.1, 0.1));
  Scenario sc;
  sc.file = dir / "cube.toml";
  sc.run.end_time = end_time;
  sc.run.time_step = time_step;
  sc.damping.alpha = 50;
  sc.materials["rubber"] = MaterialInstance{"rubber", "neo_hookean", {{{"mu", 3000.0}, {"bulk", 50000.0}, {"density", 1000.0}}, {}}};
  BodySpec body;
  body.name = "cube";
  body.mesh = dir / "cube.msh";
  body.materials["*"] = "rubber";
  sc.bodies.push_back(body);
  sc.boundaries.push_back(BoundarySpec{"cube", "zmin", {}, BoundaryType::fixed, {0, 0, 0}, {true, true, true}, {0, 0, 0}, "", "", {0, 0, 0}});
  sc.boundaries.push_back(BoundarySpec{"cube", "zmax", {}, BoundaryType::velocity, {0, 0, -0.05}, {true, true, true}, {0, 0, 0}, "", "", {0, 0, 0}});
  return sc;
}

// The times results.pvd lists, parsed back from its text.
std::vector<double> pvd_times(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  const std::string text = s.str();
  std::vector<double> t;
  const std::regex re(R"re(timestep="([^"]+)")re");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), re); it != std::sregex_iterator(); ++it) t.push_back(std::stod((*it)[1]));
  return t;
}

void expect_exact_states(const RunSummary& s, const std::filesystem::path& out, const std::vector<double>& expected) {
  // The initial state (t = 0) comes first, then the scheduled ones.
  const std::vector<double> listed = pvd_times(out / "results.pvd");
  ASSERT_EQ(listed.size(), expected.size() + 1);
  EXPECT_EQ(listed[0], 0.0);
  EXPECT_TRUE(std::filesystem::is_regular_file(out / "results" / "state_0000.vtu"));
  for (std::size_t k = 0; k < expected.size(); ++k) EXPECT_EQ(listed[k + 1], expected[k]) << "state " << k + 1;  // exact (12 digits written)
  const auto& j = s.run_json;
  EXPECT_EQ(j["end_time"].get<double>(), expected.back());
  EXPECT_EQ(j["outputs"].get<std::size_t>(), expected.size() + 1);
  EXPECT_GE(j["time_step"]["min_ratio_to_nominal"].get<double>(), 0.5);
  for (std::size_t k = 0; k < expected.size(); ++k)
    EXPECT_EQ(j["output_times"][k].get<double>(), expected[k]);  // the solver's own times: exact to the bit
}

}  // namespace

// The landing rule itself (schedule.hpp): one step when at most one nominal step remains, two
// equal halves when less than two remain, the nominal step otherwise.
TEST(Schedule, LandingStepRule) {
  const double h = 1e-4;
  auto c = choose_landing_step(5 * h, h, 2 * h);
  EXPECT_EQ(c.dt, h);
  EXPECT_FALSE(c.lands);
  c = choose_landing_step(1.5 * h, h, 2 * h);
  EXPECT_EQ(c.dt, 0.75 * h);
  EXPECT_FALSE(c.lands);
  c = choose_landing_step(0.75 * h, h, 2 * h);
  EXPECT_EQ(c.dt, 0.75 * h);
  EXPECT_TRUE(c.lands);
  c = choose_landing_step(h * (1 + 1e-12), h, 2 * h);  // the round-off of summed steps: one step
  EXPECT_TRUE(c.lands);
  c = choose_landing_step(h * (1 + 1e-12), h, h);  // never above the stable limit
  EXPECT_FALSE(c.lands);
  EXPECT_LE(c.dt, h);
  EXPECT_GE(c.dt, 0.5 * h);
}

TEST(Schedule, IntervalTimesComeFromKNotFromASum) {
  RunSpec r;
  r.end_time = 1.0;
  r.output_interval = 0.1;
  r.output_times = {0.25};
  const auto t = output_schedule(r);
  ASSERT_EQ(t.size(), 11u);
  for (int k = 1; k <= 10; ++k) {
    const double expected = k == 10 ? 1.0 : k * 0.1;
    EXPECT_EQ(t[static_cast<std::size_t>(k < 3 ? k - 1 : k)], expected);
  }
  EXPECT_EQ(t[2], 0.25);
}

// The issue's case: fixed step 1e-4 to 0.2 s with the default output (the end time).
TEST(Schedule, FixedStepToEndTimeWritesTheEndState) {
  testkit::TempDir dir;
  const RunSummary s = run_simulation(cube(dir.path(), 0.2, 1e-4), dir / "out");
  std::printf("1e-4 to 0.2 s: %zu steps, end time %.17g, min step %.17g, max %.17g\n", s.steps, s.end_time, s.dt_min, s.dt_max);
  EXPECT_EQ(s.steps, 2000u);
  expect_exact_states(s, dir / "out", {0.2});
}

// 3e-5 does not divide 0.1: the last 4e-5 s are two steps of 2e-5 (two thirds of the nominal).
TEST(Schedule, FixedStepThatDoesNotDivideTheEndTime) {
  testkit::TempDir dir;
  Scenario sc = cube(dir.path(), 0.1, 3e-5);
  sc.run.output_times = {0.05, 0.1};
  const RunSummary s = run_simulation(sc, dir / "out");
  std::printf("3e-5 to 0.1 s: %zu steps, min step %.6g (ratio %.4f), states at 0.05 and 0.1 s exactly\n", s.steps, s.dt_min,
              s.run_json["time_step"]["min_ratio_to_nominal"].get<double>());
  // Each half: 1665 full steps, then the 5e-5 s left (between one and two steps) as two of 2.5e-5.
  EXPECT_EQ(s.steps, 3334u);
  expect_exact_states(s, dir / "out", {0.05, 0.1});
}

// Automatic step, an output interval that the step does not divide: each state once, exactly at k * interval.
TEST(Schedule, AutomaticStepOutputInterval) {
  testkit::TempDir dir;
  Scenario sc = cube(dir.path(), 0.05, 0);
  sc.run.output_interval = 0.0123;
  const RunSummary s = run_simulation(sc, dir / "out");
  std::printf("automatic step, every 0.0123 s to 0.05 s: %zu steps, dt %.6g..%.6g, %zu states\n", s.steps, s.dt_min, s.dt_max, s.outputs);
  expect_exact_states(s, dir / "out", {0.0123, 2 * 0.0123, 3 * 0.0123, 4 * 0.0123, 0.05});
}

// --check: every figure within its tolerance passes; one figure moved beyond its tolerance fails,
// named; a figure the reference lacks fails too.
TEST(Schedule, ReferenceCheckNamesTheFigureThatMoved) {
  testkit::TempDir dir;
  const RunSummary s = run_simulation(cube(dir.path(), 0.01, 1e-4), dir / "out");
  nlohmann::json ref = make_reference(s.run_json, "cube");
  for (const auto& c : check_reference(s.run_json, ref, "ref.json")) EXPECT_TRUE(c.ok) << c.name;
  const double k = ref["figures"]["energy.kinetic"]["value"].get<double>();
  ref["figures"]["energy.kinetic"]["value"] = k * (1 + 2e-6);  // beyond the 1e-6 tolerance
  ref["figures"]["peak_von_mises.rubber"]["value"] = ref["figures"]["peak_von_mises.rubber"]["value"].get<double>() * 1.005;  // within 1 %
  std::vector<std::string> failed;
  for (const auto& c : check_reference(s.run_json, ref, "ref.json"))
    if (!c.ok) failed.push_back(c.name);
  EXPECT_EQ(failed, std::vector<std::string>{"energy.kinetic"});
  std::printf("%s", format_checks(check_reference(s.run_json, ref, "ref.json")).c_str());
  ref["figures"].erase("steps");
  failed.clear();
  for (const auto& c : check_reference(s.run_json, ref, "ref.json"))
    if (!c.ok) failed.push_back(c.name);
  EXPECT_EQ(failed, (std::vector<std::string>{"energy.kinetic", "steps"}));
}

// Outputs closer than half a step (output_interval 2e-10 s wrote 600 identical states a second)
// are refused, naming the two times and the step.
TEST(Schedule, OutputsCloserThanHalfAStepAreRefused) {
  testkit::TempDir dir;
  Scenario sc = cube(dir.path(), 2e-3, 1e-4);
  sc.run.output_interval = 2e-5;
  testkit::expect_input_error([&] { run_simulation(sc, dir / "out"); }, {"run.output_interval", "half a time step", "0 s and 2e-05 s"});
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}
