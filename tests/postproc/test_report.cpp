// tactus-post on a tiny hand-made results folder: a 40 x 20 x 5 mm plate ("soft") pressed by a
// 10 mm cube ("bone"), two output states, a three-row history and a run.json. Every number the
// summary reports is set here by hand, so the oracles are the values written; the pictures are
// read back as pixels (VTK's PNG reader) and checked for what they must show.
#include <gtest/gtest.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "expect_error.hpp"
#include "tactus/core/contracts.hpp"
#include "tactus/core/error.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/postproc/render.hpp"
#include "tactus/postproc/results.hpp"
#include "tactus/postproc/summary.hpp"
#include "tactus/postproc/web_report.hpp"
#include "temp_dir.hpp"

using namespace tactus;
using tactus::testkit::expect_input_error;
using tactus::testkit::TempDir;
namespace fs = std::filesystem;
namespace c = tactus::contracts;

namespace {

constexpr double kPeakPressure = 2e6;    // Pa at the plate's top node (10, 10, 5) mm, state 1
constexpr double kSidePressure = 0.5e6;  // Pa at its four neighbours
constexpr double kPunchStress = 5e6;     // Pa, every cube cell, state 1
constexpr std::size_t kPlateCells = 4 * 2 * 1 * 6;
constexpr std::size_t kFibreCell = 5;   // 0-based plate cell of the largest fibre stretch (state 1, family 2)
constexpr double kFibreStretch = 1.08;  // its isochoric stretch
constexpr double kFibreStressXX = 1e6;  // its fibre stress: uniaxial, so von Mises 1 MPa

struct Folder {
  TetMesh mesh;
  std::size_t plate_nodes = 0;
  std::size_t peak_node = 0;  // 0-based
  std::size_t soft_peak = 0;  // 0-based element of the plate's peak von Mises

  // von Mises of plate cell e in state k: grows with e, and with the state.
  static double plate_stress(std::size_t e, int k) { return (1 + k) * 1e3 * static_cast<double>(e + 1); }
};

Folder write_results(const fs::path& dir, bool contact = true) {
  Folder f;
  f.mesh = samples::make_box_mesh(4, 2, 1, 0.04, 0.02, 0.005);
  f.plate_nodes = f.mesh.nodes.size();
  samples::append_mesh(f.mesh, samples::make_box_mesh(1, 1, 1, 0.01, 0.01, 0.01, {0.015, 0.005, 0.0055}), 100, "_punch");
  const std::size_t cells = f.mesh.tets.size();
  fs::create_directories(dir / "results");
  std::ofstream pvd(dir / "results.pvd");
  pvd << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
  for (int k = 0; k < 2; ++k) {
    MeshField vm{c::cell::von_mises.name, 1, {}}, mat{c::cell::material.name, 1, {}}, body{c::cell::body.name, 1, {}};
    MeshField stretch{"fibre_stretch_isochoric", 2, std::vector<double>(2 * cells, 0.0)},
        fstress{"fibre_stress", 6, std::vector<double>(6 * cells, 0.0)};
    for (std::size_t e = 0; e < kPlateCells; ++e) stretch.values[2 * e] = 1.0 + 0.001 * static_cast<double>(e);  // family 1: below the peak
    if (k == 1) stretch.values[2 * kFibreCell + 1] = kFibreStretch, fstress.values[6 * kFibreCell] = kFibreStressXX;
    for (std::size_t e = 0; e < cells; ++e) {
      const bool plate = e < kPlateCells;
      vm.values.push_back(plate ? Folder::plate_stress(e, k) : k * kPunchStress);
      mat.values.push_back(plate ? 0 : 1);
      body.values.push_back(plate ? 0 : 1);
    }
    MeshField p{c::point::contact_pressure.name, 1, std::vector<double>(f.mesh.nodes.size(), 0.0)};
    // State 0: first touch at the peak node only (a quarter of its final pressure); state 1: the
    // peak there and its four neighbours, so the peak moves up at the same node between states.
    for (std::size_t i = 0; i < f.plate_nodes && contact; ++i) {
      const auto& x = f.mesh.nodes[i];
      if (std::abs(x[2] - 0.005) > 1e-12) continue;
      const double d = std::hypot(x[0] - 0.01, x[1] - 0.01);
      if (d < 1e-9)
        p.values[i] = k == 1 ? kPeakPressure : 0.25 * kPeakPressure, f.peak_node = i;
      else if (std::abs(d - 0.01) < 1e-9 && k == 1)
        p.values[i] = kSidePressure;
    }
    // A grasp's region per node: the plate's nodes are one finger segment, the punch's none.
    MeshField region{c::point::grip_region.name, 1, std::vector<double>(f.mesh.nodes.size(), -1.0)};
    for (std::size_t i = 0; i < f.plate_nodes; ++i) region.values[i] = 0;
    const std::string name = "results/state_000" + std::to_string(k) + ".vtu";
    write_vtu(dir / name, f.mesh, {p, region}, {vm, mat, body, stretch, fstress}, nullptr, std::nullopt,
              {{c::kGripRegionNames, {"distal_phalanx_index"}}});
    pvd << "<DataSet timestep=\"" << k * 1e-3 << "\" group=\"\" part=\"0\" file=\"" << name << "\"/>\n";
  }
  pvd << "</Collection>\n</VTKFile>\n";
  f.soft_peak = kPlateCells - 1;

  std::ofstream h(dir / "history.csv");
  for (std::size_t k = 0; k < c::history::all.size(); ++k) h << (k ? "," : "") << c::history::all[k]->name;
  for (const char* axis : {"_x", "_y", "_z"}) h << "," << c::history::reaction.prefix << "base" << axis;  // one [[boundary]] named base
  h << "\n";
  const double time[3] = {0, 0.5e-3, 1e-3}, force[3] = {0, 50, 120}, kinetic[3] = {2.0, 1.5, 1.0};
  for (int r = 0; r < 3; ++r) {
    for (std::size_t k = 0; k < c::history::all.size(); ++k) {
      const std::string col = c::history::all[k]->name;
      double v = 0;
      if (col == c::history::step.name) v = r * 10;
      if (col == c::history::time.name) v = time[r];
      if (col == c::history::kinetic_energy.name) v = kinetic[r];
      if (col == c::history::internal_energy.name) v = 2.0 - kinetic[r];
      if (col == c::history::contact_force.name) v = contact ? force[r] : 0;
      if (col == c::history::contact_area.name) v = contact ? r * 1e-4 : 0;
      if (col == c::history::peak_pressure.name) v = contact ? r * 1e6 : 0;
      h << (k ? "," : "") << v;
    }
    h << "," << 0.0 << "," << 0.0 << "," << -force[r];  // the base holds the punch's push
    h << "\n";
  }
  nlohmann::json run = {
      {c::run_json::status, "completed"},
      {c::run_json::message, nullptr},
      {c::run_json::materials, {"soft", "bone"}},
      {c::run_json::bodies, {"plate", "punch"}},
      {c::run_json::steps, 20},
      {c::run_json::nodes, f.mesh.nodes.size()},
      {c::run_json::tets, cells},
      {c::run_json::end_time, 1e-3},
      {c::run_json::wall_time, 0.25},
      {c::run_json::time_step, {{"min", 4e-5}, {"max", 5e-5}}},
      {c::run_json::energy, {{"initial", 2.0}, {"balance_error", -0.01}, {"contact_work_normal", 0.3}, {"contact_work_friction", 0.1}}},
      {c::run_json::contact,
       {{"steps_in_contact", contact ? 7 : 0},
        {"pairs",
         {{{"name", "contact[0] punch/surface -> plate/top"},
           {"peak_force", {{"value", 125.0}, {"time", 0.9e-3}}},
           {"peak_area", {{"value", 2.5e-4}, {"time", 0.95e-3}}},
           {"peak_pressure", {{"value", 3e6}, {"time", 0.8e-3}}}}}},
        {"peak_force", {{"value", 130.0}, {"time", 0.9e-3}}},
        {"peak_area", {{"value", 2.5e-4}, {"time", 0.95e-3}}},
        {"peak_pressure", {{"value", 3e6}, {"time", 0.8e-3}, {"position", {0.01, 0.01, 0.005}}, {"node", f.peak_node + 1}}}}},
      {c::run_json::mass_scaling,
       {{"minimum_time_step", 4e-5},
        {"added_mass_limit", 0.01},
        {"bodies",
         {{"plate", {{"mass", 4.0}, {"added_mass", 0.02}, {"fraction", 0.005}}},
          {"punch", {{"mass", 1.0}, {"added_mass", 0.0}, {"fraction", 0.0}}}}}}},
      {c::run_json::reactions,
       {{{"name", "base"},
         {"moment_about", {0, 0, 0}},
         {"final_force", {0, 0, -120}},
         {"final_moment", {1.2, -0.6, 0}},
         {"peak_force", {{"value", 120.0}, {"time", 1e-3}, {"vector", {0, 0, -120}}}}}}}};
  std::ofstream(dir / "run.json") << run.dump(2);
  return f;
}

std::array<double, 3> centroid(const TetMesh& m, std::size_t e) {
  std::array<double, 3> x{0, 0, 0};
  for (int v : m.tets[e])
    for (std::size_t d = 0; d < 3; ++d) x[d] += 0.25 * m.nodes[static_cast<std::size_t>(v)][d];
  return x;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST(Summary, PeaksAndTimesAreTheWrittenOnes) {
  TempDir tmp;
  const Folder f = write_results(tmp.path() / "solve");
  const auto results = postproc::read_results(tmp.path() / "solve");
  const auto s = postproc::summarize(results);
  ASSERT_EQ(s.von_mises.size(), 2u);
  EXPECT_EQ(s.von_mises[0].material, "soft");
  EXPECT_DOUBLE_EQ(s.von_mises[0].von_mises.value, Folder::plate_stress(f.soft_peak, 1));
  EXPECT_DOUBLE_EQ(s.von_mises[0].von_mises.time, 1e-3);
  EXPECT_EQ(s.von_mises[0].von_mises.index, static_cast<long>(f.soft_peak) + 1);
  const auto at = centroid(f.mesh, f.soft_peak);
  for (std::size_t d = 0; d < 3; ++d) EXPECT_NEAR(s.von_mises[0].von_mises.position[d], at[d], 1e-15);
  EXPECT_DOUBLE_EQ(s.von_mises[1].von_mises.value, kPunchStress);

  EXPECT_TRUE(s.contact_occurred);
  EXPECT_DOUBLE_EQ(s.peak_pressure_outputs.value, kPeakPressure);
  EXPECT_EQ(s.peak_pressure_outputs.index, static_cast<long>(f.peak_node) + 1);
  EXPECT_NEAR(s.peak_pressure_outputs.position[0], 0.01, 1e-15);
  EXPECT_NEAR(s.peak_pressure_outputs.position[1], 0.01, 1e-15);
  EXPECT_EQ(s.peak_pressure_outputs.body, "plate");    // the body of the cells around the peak node
  EXPECT_DOUBLE_EQ(s.peak_pressure_steps.value, 3e6);  // run.json: every step
  EXPECT_DOUBLE_EQ(s.peak_force.value, 130.0);
  EXPECT_DOUBLE_EQ(s.largest_area.value, 2.5e-4);

  ASSERT_EQ(s.frames.size(), 2u);
  EXPECT_EQ(s.frames[0].contact_nodes, 1u);          // the first touch
  EXPECT_EQ(s.frames[1].contact_nodes, 5u);          // the peak node and its four neighbours
  EXPECT_DOUBLE_EQ(s.frames[1].contact_force, 120);  // the history row at 1 ms
  EXPECT_DOUBLE_EQ(s.frames[0].contact_force, 0);
  EXPECT_DOUBLE_EQ(s.frames[1].von_mises_max[1], kPunchStress);
  EXPECT_DOUBLE_EQ(s.initial_kinetic, 2.0);
  ASSERT_EQ(s.reactions.size(), 1u);  // run.json reactions
  EXPECT_EQ(s.reactions[0].name, "base");
  EXPECT_DOUBLE_EQ(s.reactions[0].peak, 120.0);
  EXPECT_DOUBLE_EQ(s.reactions[0].final_force[2], -120.0);
  EXPECT_DOUBLE_EQ(s.reactions[0].final_moment[0], 1.2);

  EXPECT_DOUBLE_EQ(s.fibre_stretch.value, kFibreStretch);
  EXPECT_EQ(s.fibre_family, 2);
  EXPECT_EQ(s.fibre_stretch.index, static_cast<long>(kFibreCell) + 1);
  EXPECT_DOUBLE_EQ(s.fibre_stretch.time, 1e-3);
  EXPECT_DOUBLE_EQ(s.fibre_stress_there, kFibreStressXX);

  const auto j = nlohmann::json::parse(postproc::summary_json(s));
  std::cout << "summary: soft peak " << j["peak_von_mises"]["soft"]["value"] << " Pa, pressure at outputs "
            << j["contact"]["peak_pressure_at_outputs"]["value"] << " Pa, balance " << j["energy"]["balance_error_of_initial_kinetic"] << "\n";
  EXPECT_DOUBLE_EQ(j["energy"]["balance_error_of_initial_kinetic"].get<double>(), 0.01 / 2.0);
  EXPECT_DOUBLE_EQ(j["contact"]["peak_pressure_at_outputs"]["value"].get<double>(), kPeakPressure);
  const std::string md = postproc::summary_markdown(s);
  EXPECT_NE(md.find("| soft | 0.096 | 1 | element 48, "), std::string::npos) << md;  // 96 kPa at 1 ms
  EXPECT_NE(md.find("| peak contact force, one step | 130 N |"), std::string::npos) << md;
  EXPECT_NE(md.find("| contact[0] punch/surface -> plate/top | 125 | 0.9 | 250 | 3 |"), std::string::npos) << md;
  EXPECT_NE(md.find("Mass scaling kept the step at or above 4e-05 s, adding: plate 0.02 kg (0.5 % of its mass); punch 0 kg (0 % of its mass);"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("Largest isochoric fibre stretch (sqrt(J4bar), hgo) over the output states: 1.08 (family 2) at t = 1 ms, element 6"),
            std::string::npos)
      << md;
}

// A grasp's run.json (joints.grasp): the grip, the hold and each region's and digit's share come
// into the summary and its tables as the solver wrote them.
TEST(Summary, GraspSharesAreTheWrittenOnes) {
  TempDir tmp;
  write_results(tmp.path() / "solve");
  auto j = nlohmann::json::parse(slurp(tmp.path() / "solve" / "run.json"));
  nlohmann::json regions = nlohmann::json::array(), digits = nlohmann::json::array();
  regions.push_back({{"name", "distal_phalanx_index"},
                     {"digit", "index"},
                     {"normal_force", 30.0},
                     {"share", 0.6},
                     {"area", 1.5e-4},
                     {"peak_pressure", 4e5},
                     {"averaged_peak_pressure", 3e5}});
  regions.push_back({{"name", "palm_central"},
                     {"digit", "palm"},
                     {"normal_force", 20.0},
                     {"share", 0.4},
                     {"area", 4e-4},
                     {"peak_pressure", 1e5},
                     {"averaged_peak_pressure", 8e4}});
  digits.push_back({{"name", "index"}, {"normal_force", 30.0}, {"share", 0.6}});
  digits.push_back({{"name", "palm"}, {"normal_force", 20.0}, {"share", 0.4}});
  j["joints"] = {{"joints", nlohmann::json::array()},
                 {"grasp",
                  {{"handle", "punch"},
                   {"target_force", 50.0},
                   {"final_grip_force", 49.0},
                   {"max_kinetic_to_strain_energy_in_hold", 0.08},
                   {"quasi_static", false},
                   {"hold_from", 0.15},
                   {"regions", {{"regions", regions}, {"digits", digits}, {"pressure_average_area", 2.5e-5}}}}}};
  std::ofstream(tmp.path() / "solve" / "run.json") << j.dump(2);
  const auto s = postproc::summarize(postproc::read_results(tmp.path() / "solve"));
  ASSERT_TRUE(s.grasp.on);
  EXPECT_DOUBLE_EQ(s.grasp.final_grip, 49.0);
  ASSERT_EQ(s.grasp.regions.size(), 2u);
  EXPECT_DOUBLE_EQ(s.grasp.regions[0].averaged_peak_pressure, 3e5);
  const std::string md = postproc::summary_markdown(s);
  std::cout << md.substr(md.find("## Grasp"), 600) << "\n";
  EXPECT_NE(md.find("49 N at the end against a target of 50 N (-2 %)"), std::string::npos) << md;
  EXPECT_NE(md.find("**dynamic**"), std::string::npos) << md;
  EXPECT_NE(md.find("| index | 30 | 60 % |"), std::string::npos) << md;
  EXPECT_NE(md.find("| distal_phalanx_index | index | 30 | 60 % | 150 | 0.4 | 0.3 |"), std::string::npos) << md;
  EXPECT_DOUBLE_EQ(nlohmann::json::parse(postproc::summary_json(s))["grasp"]["digits"][1]["share"].get<double>(), 0.4);
  // The interactive page's grip table carries the same numbers (no pictures drawn: no map).
  postproc::write_web_report(postproc::read_results(tmp.path() / "solve"), s, tmp.path() / "report");
  std::string model = slurp(tmp.path() / "report/data/model.js");
  const auto page = nlohmann::json::parse(model.substr(model.find('(') + 1, model.rfind(')') - model.find('(') - 1))["grasp"];
  ASSERT_EQ(page["regions"].size(), 2u);
  EXPECT_EQ(page["regions"][1]["name"], "palm_central");
  EXPECT_DOUBLE_EQ(page["regions"][0]["force_N"].get<double>(), 30.0);
  EXPECT_DOUBLE_EQ(page["regions"][0]["share"].get<double>(), 0.6);
  EXPECT_DOUBLE_EQ(page["regions"][1]["averaged_peak_pressure_Pa"].get<double>(), 8e4);
  EXPECT_DOUBLE_EQ(page["final_grip_N"].get<double>(), 49.0);
  EXPECT_TRUE(page["grip_map"].is_null());
}

TEST(Summary, NoContactIsSaid) {
  TempDir tmp;
  write_results(tmp.path() / "solve", false);
  const auto s = postproc::summarize(postproc::read_results(tmp.path() / "solve"));
  EXPECT_FALSE(s.contact_occurred);
  EXPECT_EQ(s.peak_pressure_outputs.value, 0);
  EXPECT_NE(postproc::summary_markdown(s).find("No contact occurred"), std::string::npos);
  EXPECT_FALSE(nlohmann::json::parse(postproc::summary_json(s))["contact"].contains("peak_force"));
}

TEST(Summary, BrokenFoldersAreNamed) {
  TempDir tmp;
  const fs::path d = tmp.path() / "solve";
  write_results(d);
  // A truncated history row: the file and the line.
  {
    std::string h = slurp(d / "history.csv");
    h = h.substr(0, h.rfind(',', h.size() - 2)) + "\n";
    std::ofstream(d / "history.csv") << h;
    expect_input_error([&] { postproc::read_results(d); }, {"history.csv", "line 4", "truncated"});
  }
  write_results(d);
  // A wrong type in run.json: the key.
  {
    auto j = nlohmann::json::parse(slurp(d / "run.json"));
    j[c::run_json::steps] = "many";
    std::ofstream(d / "run.json") << j.dump();
    expect_input_error([&] { postproc::read_results(d); }, {"run.json", "steps", "count"});
  }
  write_results(d);
  // A material index beyond run.json's list: the state file.
  {
    auto j = nlohmann::json::parse(slurp(d / "run.json"));
    j[c::run_json::materials] = {"soft"};
    std::ofstream(d / "run.json") << j.dump();
    expect_input_error([&] { postproc::summarize(postproc::read_results(d)); }, {"state_0000.vtu", "material", "indices below 1"});
  }
}

// ---- pictures: tactus-post itself (it starts its own Xvfb), the PNGs read back --------------------

namespace {

struct Picture {
  int width = 0, height = 0;
  std::vector<std::array<int, 3>> rgb;  // row 0 at the bottom (VTK's order)
  const std::array<int, 3>& at(int x, int y) const { return rgb[static_cast<std::size_t>(y * width + x)]; }
};

Picture read_png(const fs::path& file) {
  vtkNew<vtkPNGReader> r;
  r->SetFileName(file.string().c_str());
  r->Update();
  vtkImageData* img = r->GetOutput();
  Picture p;
  int dims[3];
  img->GetDimensions(dims);
  p.width = dims[0], p.height = dims[1];
  const int n = img->GetNumberOfScalarComponents();
  const auto* data = static_cast<const unsigned char*>(img->GetScalarPointer());
  for (int i = 0; i < p.width * p.height; ++i) p.rgb.push_back({data[i * n], data[i * n + 1], data[i * n + 2]});
  return p;
}

// The lower-left corner of a 3-D picture holds its view keys (triad, "seen from", scale bar).
bool in_keys(const Picture& p, int x, int y) { return x < 0.4 * p.width && y < 0.28 * p.height; }

// The model's part of a picture: left of the colour bar (88 % of the width), between the caption
// rows at the top and the legend at the bottom, outside the keys' corner.
template <typename Pred>
std::vector<std::array<int, 2>> pixels(const Picture& p, Pred pred) {
  std::vector<std::array<int, 2>> out;
  for (int y = 60; y < p.height - 60; ++y)
    for (int x = 0; x < static_cast<int>(0.86 * p.width); ++x)
      if (!in_keys(p, x, y) && pred(p.at(x, y))) out.push_back({x, y});
  return out;
}

// The keys' corner only.
template <typename Pred>
std::size_t key_pixels(const Picture& p, Pred pred) {
  std::size_t n = 0;
  for (int y = 0; y < p.height; ++y)
    for (int x = 0; x < p.width; ++x) n += in_keys(p, x, y) && y >= 60 && pred(p.at(x, y));
  return n;
}

bool coloured(const std::array<int, 3>& c) { return std::max({c[0], c[1], c[2]}) - std::min({c[0], c[1], c[2]}) > 60; }
bool red(const std::array<int, 3>& c) { return c[0] > 200 && c[1] < 70 && c[2] < 70; }
bool black(const std::array<int, 3>& c) { return c[0] < 30 && c[1] < 30 && c[2] < 30; }
bool light_grey(const std::array<int, 3>& c) { return std::abs(c[0] - c[1]) < 6 && std::abs(c[1] - c[2]) < 6 && c[0] > 150 && c[0] < 235; }

std::array<double, 2> mean(const std::vector<std::array<int, 2>>& px) {
  std::array<double, 2> m{0, 0};
  for (const auto& q : px) m[0] += q[0], m[1] += q[1];
  for (double& v : m) v /= static_cast<double>(std::max<std::size_t>(px.size(), 1));
  return m;
}

int run_post(const fs::path& results, const fs::path& report, const std::string& options) {
  const std::string cmd = "env -u DISPLAY '" + std::string(TACTUS_POST_EXE) + "' '" + results.string() + "' -o '" + report.string() + "' -q " +
                          options + " > '" + report.string() + ".log' 2>&1";
  return std::system(cmd.c_str());
}

}  // namespace

TEST(Pictures, ShowWhatTheDataSays) {
  TempDir tmp;
  const fs::path d = tmp.path() / "solve";
  write_results(d);
  ASSERT_EQ(run_post(d, tmp.path() / "report", ""), 0) << slurp(tmp.path() / "report.log");
  ASSERT_EQ(run_post(d, tmp.path() / "edge_on", "--view 1 0 0"), 0) << slurp(tmp.path() / "edge_on.log");
  const auto summary = nlohmann::json::parse(slurp(tmp.path() / "report" / "summary.json"));
  // (the nodal von Mises at output 1, the punch's 5 MPa: the highest stress)
  std::vector<std::string> expected{"von_mises_t0.00ms.png", "von_mises_t1.00ms.png",  "von_mises_nodal_t1.00ms.png", "section.png",
                                    "pressure.png",          "pressure_t0.00ms.png",   "pressure_t1.00ms.png",        "plot_contact_force.png",
                                    "plot_contact_area.png", "plot_peak_pressure.png", "plot_energies.png",           "plot_reactions.png"};
  EXPECT_EQ(summary["pictures"].get<std::vector<std::string>>(), expected);

  // The stress picture looks along the plate's thinnest axis (z), so the plate shows its 40 x 20
  // mm face; seen edge-on along x (--view 1 0 0) it shows 20 x 5 mm plus the cube's 10 x 10 mm:
  // a quarter of the area at the same camera distance, less the perspective's enlargement of the
  // near end (the camera is about 4 plate half-lengths away: the end face grows by ~1.6).
  const Picture top = read_png(tmp.path() / "report" / "von_mises_t1.00ms.png");
  const Picture side = read_png(tmp.path() / "edge_on" / "von_mises_t1.00ms.png");
  EXPECT_EQ(top.width, 1200);
  EXPECT_EQ(top.height, 900);
  const double a_top = static_cast<double>(pixels(top, coloured).size()), a_side = static_cast<double>(pixels(side, coloured).size());
  std::cout << "coloured pixels: default view " << a_top << ", edge-on " << a_side << " (ratio " << a_top / a_side << ", areas 800 : 200 mm^2)\n";
  EXPECT_GT(a_top, 2.0 * a_side);
  EXPECT_LT(a_top, 5.0 * a_side);

  // The pressure map shows the plate from its pressed (+z) side: red at the peak node (a quarter of
  // the plate's length from its end, so away from the picture's centre), the black dot on it,
  // unpressed grey around.
  const Picture pressure = read_png(tmp.path() / "report" / "pressure.png");
  const auto reds = pixels(pressure, red), dots = pixels(pressure, black), greys = pixels(pressure, light_grey);
  const auto r = mean(reds), b = mean(dots);
  std::cout << "pressure picture: " << reds.size() << " red pixels around (" << r[0] << ", " << r[1] << "), black dot at (" << b[0] << ", " << b[1]
            << "), " << greys.size() << " grey\n";
  ASSERT_FALSE(reds.empty());
  ASSERT_FALSE(dots.empty());
  EXPECT_GT(greys.size(), reds.size());
  EXPECT_LT(std::hypot(r[0] - b[0], r[1] - b[1]), 0.03 * pressure.width);
  EXPECT_GT(std::hypot(r[0] - 0.5 * pressure.width, r[1] - 0.5 * pressure.height), 0.1 * pressure.width);
  // Its keys: the triad's green y axis and the black scale bar with its label, in the corner.
  const auto green = [](const std::array<int, 3>& c) { return c[1] > 150 && c[0] < 90 && c[2] < 90; };
  const std::size_t triad = key_pixels(pressure, green), ink = key_pixels(pressure, black);
  std::cout << "view keys: " << triad << " green triad pixels, " << ink << " black (scale bar, labels)\n";
  EXPECT_GT(triad, 20u);
  EXPECT_GT(ink, 200u);

  // One pressure picture per output with contact, on one colour scale (0 to the outputs' peak) and
  // one view: the 1 ms state is the peak state, so its picture is pressure.png pixel for pixel; at
  // 0 ms the same node carries a quarter of the peak, so it shows cyan (hue 0.25 of the way up the
  // rainbow), no red, and the dot at the same place.
  const Picture last = read_png(tmp.path() / "report" / "pressure_t1.00ms.png");
  const Picture first = read_png(tmp.path() / "report" / "pressure_t0.00ms.png");
  EXPECT_EQ(last.rgb, pressure.rgb);
  const auto cyan = [](const std::array<int, 3>& c) { return c[0] < 90 && c[1] > 160 && c[2] > 160; };
  const auto first_reds = pixels(first, red), first_cyans = pixels(first, cyan), first_dots = pixels(first, black);
  const auto c0 = mean(first_cyans), b0 = mean(first_dots);
  std::cout << "pressure at 0 ms on the common scale: " << first_reds.size() << " red, " << first_cyans.size() << " cyan pixels around (" << c0[0]
            << ", " << c0[1] << "), black dot at (" << b0[0] << ", " << b0[1] << ")\n";
  EXPECT_TRUE(first_reds.empty());
  ASSERT_FALSE(first_cyans.empty());
  ASSERT_FALSE(first_dots.empty());
  EXPECT_LT(std::hypot(c0[0] - b0[0], c0[1] - b0[1]), 0.03 * first.width);
  EXPECT_LT(std::hypot(b0[0] - b[0], b0[1] - b[1]), 0.01 * first.width);

  // The force plot draws its one line in the first plot colour.
  const Picture plot = read_png(tmp.path() / "report" / "plot_contact_force.png");
  EXPECT_EQ(plot.width, 900);
  const auto line = pixels(plot, [](const std::array<int, 3>& c) { return std::abs(c[0] - 31) < 30 && std::abs(c[1] - 119) < 30 && c[2] > 150; });
  std::cout << "force plot: " << line.size() << " line pixels\n";
  EXPECT_GT(line.size(), 200u);
}

TEST(Pictures, UnknownPressureBodyIsRefused) {
  TempDir tmp;
  write_results(tmp.path() / "solve");
  EXPECT_NE(run_post(tmp.path() / "solve", tmp.path() / "report", "--pressure-body hand"), 0);
  const std::string log = slurp(tmp.path() / "report.log");
  EXPECT_NE(log.find("--pressure-body"), std::string::npos) << log;
  EXPECT_NE(log.find("plate, punch"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(tmp.path() / "report"));
}

// The pressure pictures' colour cap (render.hpp). Oracle: the definition on hand-made sets - 1,000
// nodes of 1 mm² at 0.1..100 kPa in steps of 0.1 kPa (the cap is the 995th value, 99.5 kPa), the
// same plus one node of 1.69 MPa on 2 mm² (0.2 % of the area: the cap stays 99.7 kPa, the 997th
// of the pooled list), and that node on 10 mm² (1 % of the area: the cap is its pressure).
TEST(Pictures, PressureScaleIsCappedAtTheAreaPercentile) {
  std::vector<std::pair<double, double>> pressed;
  for (int i = 1; i <= 1000; ++i) pressed.emplace_back(100.0 * i, 1e-6);
  const double plain = postproc::pressure_scale_cap(pressed);
  auto with_hot = pressed;
  with_hot.emplace_back(1.69e6, 2e-6);
  const double capped = postproc::pressure_scale_cap(with_hot);
  auto wide_hot = pressed;
  wide_hot.emplace_back(1.69e6, 10e-6);
  const double wide = postproc::pressure_scale_cap(wide_hot);
  std::printf("pressure cap: %.1f kPa (expected 99.5), with a 1.69 MPa node on 0.2 %% of the area %.1f kPa (99.7), on 1 %% %.3f MPa (1.69)\n",
              plain / 1e3, capped / 1e3, wide / 1e6);
  EXPECT_DOUBLE_EQ(plain, 99500.0);
  EXPECT_DOUBLE_EQ(capped, 99700.0);
  EXPECT_DOUBLE_EQ(wide, 1.69e6);
  EXPECT_EQ(postproc::pressure_scale_cap({}), 0.0);
}

// The interactive report's colour cap: the histogram's percentile against the exact one
// (pressure_scale_cap sorts every pair), on values spread over five decades.
TEST(WebReport, PercentileCapIsTheWeightedPercentile) {
  std::vector<std::pair<double, double>> pairs;
  postproc::PercentileCap cap;
  unsigned state = 12345;
  auto uniform = [&] { return ((state = state * 1103515245u + 12345u) >> 8) / 16777216.0; };
  for (int i = 0; i < 20000; ++i) {
    const double value = std::pow(10.0, 1 + 5 * uniform()), weight = 0.5 + uniform();
    pairs.emplace_back(value, weight);
    cap.add(value, weight);
  }
  const double exact = postproc::pressure_scale_cap(pairs);
  std::printf("99.5 %% weighted percentile: histogram %.6g, exact %.6g (ratio %.5f; one bin is 1.00577)\n", cap.cap(), exact, cap.cap() / exact);
  EXPECT_GE(cap.cap(), exact);
  EXPECT_LE(cap.cap(), exact * std::pow(10.0, 1.0 / 400) * (1 + 1e-12));
}

// The page's data: the boundary surface of the plate and the punch (2 triangles per cell face on
// the box surfaces: 2 x (4x2 + 4x1 + 2x1) x 2 + 6 x 2 = 68), every output, the pressure peak the
// written one; a tiny byte budget coarsens the surface but keeps the pressed nodes' faces.
TEST(WebReport, SurfaceStatesAndCoarsening) {
  TempDir dir;
  const Folder f = write_results(dir.path());
  const postproc::Results r = postproc::read_results(dir.path());
  const postproc::Summary s = postproc::summarize(r);
  const postproc::WebReport full = postproc::write_web_report(r, s, dir.path() / "report");
  EXPECT_EQ(full.surface_faces, 68u);
  EXPECT_EQ(full.faces_shown, 68u);
  EXPECT_TRUE(full.missing.empty());
  for (const char* file : {"index.html", "tactus-report.js", "three-report.min.js", "data/model.js", "data/state_0000.js", "data/state_0001.js"})
    EXPECT_TRUE(fs::is_regular_file(dir.path() / "report" / file)) << file;
  std::string model = slurp(dir.path() / "report/data/model.js");
  model = model.substr(model.find('(') + 1, model.rfind(')') - model.find('(') - 1);
  const nlohmann::json j = nlohmann::json::parse(model);
  EXPECT_EQ(j["states"].size(), 2u);
  EXPECT_DOUBLE_EQ(j["fields"]["pressure"]["peak"]["value"].get<double>(), kPeakPressure);
  EXPECT_EQ(j["fields"]["pressure"]["peak"]["id"].get<long>(), static_cast<long>(f.peak_node) + 1);
  EXPECT_DOUBLE_EQ(j["fields"]["von_mises"]["peak"]["value"].get<double>(), kPunchStress);
  // The pressure table of the last output: the peak node and its four neighbours, each in the
  // plate's grip region (the states' grip_region and grip_region_names).
  EXPECT_TRUE(fs::is_regular_file(dir.path() / "report/pressure_1.00ms.csv"));
  std::stringstream table(slurp(dir.path() / "report/pressure_1.00ms.csv"));
  std::string line;
  int rows = -1;
  while (std::getline(table, line)) {
    EXPECT_EQ(line.substr(line.rfind(',') + 1), rows < 0 ? "region" : "distal_phalanx_index") << line;
    ++rows;
  }
  EXPECT_EQ(rows, 5);

  postproc::WebReportOptions tiny;
  tiny.byte_budget = 1;
  const postproc::WebReport coarse = postproc::write_web_report(r, s, dir.path() / "coarse", tiny);
  std::printf("surface %zu triangles, %zu bytes; with a 1-byte budget %zu triangles, %zu bytes\n", full.surface_faces, full.bytes, coarse.faces_shown,
              coarse.bytes);
  EXPECT_LT(coarse.faces_shown, full.faces_shown);
  EXPECT_LT(coarse.bytes, full.bytes);
  std::string cm = slurp(dir.path() / "coarse/data/model.js");
  EXPECT_NE(cm.find("\"cluster_size\""), std::string::npos);
}

// A state file gone from a results folder: the report leaves it out, says so, and reports the rest.
TEST(Summary, MissingStateIsSaidAndTheRestReported) {
  TempDir tmp;
  const fs::path d = tmp.path() / "solve";
  write_results(d);
  fs::remove(d / "results/state_0000.vtu");
  const postproc::Results r = postproc::read_results(d);
  ASSERT_EQ(r.frames.size(), 1u);
  EXPECT_DOUBLE_EQ(r.frames[0].time, 1e-3);
  ASSERT_EQ(r.missing.size(), 1u);
  EXPECT_NE(r.missing[0].find("state_0000.vtu"), std::string::npos) << r.missing[0];
  const postproc::Summary s = postproc::summarize(r);
  EXPECT_NE(postproc::summary_markdown(s).find("Missing output states"), std::string::npos);
  EXPECT_DOUBLE_EQ(s.peak_pressure_outputs.value, kPeakPressure);
  fs::remove(d / "results/state_0001.vtu");
  expect_input_error([&] { postproc::read_results(d); }, {"results.pvd", "every state file is missing"});
}
