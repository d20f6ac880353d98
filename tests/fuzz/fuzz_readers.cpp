// tactus-fuzz: deterministic mutation fuzzing of every reader of user files. For each reader a
// valid input is made, then mutated N times (bit flips, interesting bytes and numbers, inserted,
// deleted, duplicated and truncated runs, duplicated and dropped lines), each mutation read in a
// forked child with a time and memory limit. Outcomes: accepted, refused (a tactus error: the
// expected answer to corrupt input), or a failure: crash (signal), hang (time limit) or internal
// error (an exception that is not a tactus error). Failing inputs are saved for regression tests.
//
//   tactus-fuzz [--readers a,b,..] [--mutations N] [--seed S] [--save DIR]
//   tactus-fuzz --replay READER FILE...     (the regression corpus: each file in place of the seed)
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/mesh.hpp"
#include "tactus/core/output.hpp"
#include "tactus/core/state_file.hpp"
#include "tactus/core/volume.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/data_samples/phantom.hpp"
#include "tactus/postproc/results.hpp"
#include "tactus/postproc/summary.hpp"
#include "tactus/segment/dicom.hpp"
#include "tactus/segment/stack.hpp"
#include "tactus/segment/volume_files.hpp"
#include "tactus/solver/checkpoint.hpp"
#include "tactus/solver/decomposition.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/model_build.hpp"
#include "tactus/solver/run.hpp"
#include "tactus/solver/scenario.hpp"

namespace fs = std::filesystem;
using namespace tactus;

namespace {

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}
void write_file(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary | std::ios::trunc) << s; }

// One reader under test: a folder with a valid input, the file in it that gets mutated, and the
// call that reads it.
struct Target {
  Target(std::string target_name, fs::path target_file, bool is_text, std::function<void()> reader)
      : name(std::move(target_name)), file(std::move(target_file)), text(is_text), read(std::move(reader)) {}
  std::string name;
  fs::path file;               // mutated in place (the seed restored before each mutation)
  bool text = false;           // text mutations (numbers, lines) in addition to bytes
  std::function<void()> read;  // throws tactus errors on bad input
  // Applied after mutating: lets mutations through a format's checksums to the decoder behind them.
  std::function<std::string(std::string)> fixup = [](std::string s) { return s; };
  // A structure-aware mutator in place of the byte and text ones (seed -> mutated input), when set.
  std::function<std::string(const std::string&, std::uint64_t)> mutator;
};

// Recomputes every PNG chunk CRC that the chunk structure still allows, so the mutated image data
// reaches the decoder (in its isolated child) instead of stopping at tactus's CRC check.
std::string fix_png_crcs(std::string s) {
  auto crc32 = [](const unsigned char* p, std::size_t n) {
    std::uint32_t c = 0xFFFFFFFFu;
    for (std::size_t i = 0; i < n; ++i) {
      c ^= p[i];
      for (int k = 0; k < 8; ++k) c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    }
    return ~c;
  };
  std::size_t pos = 8;
  auto* u = reinterpret_cast<unsigned char*>(s.data());
  while (pos + 12 <= s.size()) {
    const std::uint32_t len = (std::uint32_t{u[pos]} << 24) | (std::uint32_t{u[pos + 1]} << 16) | (std::uint32_t{u[pos + 2]} << 8) | u[pos + 3];
    if (len > s.size() - pos - 12) break;
    const std::uint32_t c = crc32(u + pos + 4, len + 4);
    for (int k = 0; k < 4; ++k) u[pos + 8 + len + k] = static_cast<unsigned char>(c >> (24 - 8 * k));
    pos += 12 + len;
  }
  return s;
}

// --------------------------------------------------------------------------------------------
// Seed inputs, all small so each read takes milliseconds.
const char* kScenario = R"(# two bodies, contact, boundaries, hgo with fibres
[run]
end_time = 1e-3
output_times = [5e-4, 1e-3]
time_step_safety = 0.9

[damping]
alpha = 10.0

[[bodies]]
name = "pad"
mesh = "pad.msh"
materials = { "*" = "skin" }
initial_velocity = [0.0, 0.0, -1.0]

[[bodies]]
name = "base"
mesh = "base.msh"
materials = { "*" = "bone" }
translate = [0.0, 0.0, -0.0105]

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
body = "base"
group = "zmin"
type = "fixed"

[[contact]]
slave_body = "pad"
slave_surface = "zmin"
master_body = "base"
master_surface = "zmax"
friction = 0.3
)";

// --------------------------------------------------------------------------------------------
// Structure-aware mutators.
const std::vector<std::string> kValues = {"nan",  "inf",  "-inf", "-1",    "0",      "1e300", "-1e300",  "1e-300",       "2.5",
                                          "-0.0", "1e18", "true", "\"x\"", "[1, 2]", "[]",    "{a = 1}", "[[1, 2], [3]]"};

// A checkpoint's values: one array (or record) of the state file, one or a few values changed to
// an out-of-range index, a sign flip, NaN, a huge or tiny number, or swapped with another entry;
// written back with its checksum recomputed (core/state_file.cpp).
std::string mutate_checkpoint_values(const std::string& original, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const fs::path scratch = fs::temp_directory_path() / ("tactus-fuzz-ckpt-" + std::to_string(getpid()) + ".h5");
  write_file(scratch, original);
  StateArrays a = read_state_file(scratch, "tactus-solve checkpoint");
  const int rounds = 1 + static_cast<int>(rng() % 2);
  for (int r = 0; r < rounds; ++r) {
    const int kind = static_cast<int>(rng() % 3);
    if (kind == 2 && !a.records.empty()) {  // a packed struct's field (4 aligned bytes) made -1 or huge
      auto it = std::next(a.records.begin(), static_cast<long>(rng() % a.records.size()));
      std::string& bytes = it->second;
      if (bytes.size() < 4) continue;
      const std::size_t at = 4 * (rng() % (bytes.size() / 4));
      const std::uint32_t values[] = {0xFFFFFFFFu, 0x7FFFFFFFu, 0x00100000u, 0x7FF80000u};
      std::memcpy(bytes.data() + at, &values[rng() % std::size(values)], 4);
    } else if (kind == 0 && !a.integers.empty()) {
      auto it = std::next(a.integers.begin(), static_cast<long>(rng() % a.integers.size()));
      std::vector<std::int64_t>& v = it->second;
      if (v.empty()) continue;
      static const std::int64_t values[] = {-1, -2, 1 << 20, 2147483647, -2147483648LL, 1LL << 40, 0, 3};
      const std::size_t i = rng() % v.size();
      if (rng() % 3 == 0)
        v[i] = v[i] + 1;
      else if (rng() % 4 == 0)
        std::swap(v[i], v[rng() % v.size()]);
      else
        v[i] = values[rng() % std::size(values)];
    } else if (!a.reals.empty()) {
      auto it = std::next(a.reals.begin(), static_cast<long>(rng() % a.reals.size()));
      std::vector<double>& v = it->second;
      if (v.empty()) continue;
      static const double values[] = {
          std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(), 1e300, -1e300, 1e12, -1, 0, 1e-300};
      const std::size_t i = rng() % v.size();
      if (rng() % 3 == 0)
        v[i] = -v[i] * 2;
      else
        v[i] = values[rng() % std::size(values)];
    }
  }
  write_state_file(scratch, a);
  std::string out = read_file(scratch);
  fs::remove(scratch);
  return out;
}

// A text as its lines, and back (the structure mutators edit whole lines).
std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream ss(text);
  for (std::string l; std::getline(ss, l);) lines.push_back(l);
  return lines;
}
std::string join_lines(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) out += l + '\n';
  return out;
}

// A TOML scenario: on a random "key = value" line, the value replaced by one of the wrong type
// or an extreme number, two keys' values swapped, two keys' names swapped, or a key dropped.
std::string mutate_toml_structure(const std::string& original, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<std::string> lines = split_lines(original);
  std::vector<std::size_t> keyed;
  for (std::size_t i = 0; i < lines.size(); ++i)
    if (lines[i].find(" = ") != std::string::npos && lines[i][0] != '#') keyed.push_back(i);
  const int rounds = 1 + static_cast<int>(rng() % 3);
  for (int r = 0; r < rounds && !keyed.empty(); ++r) {
    std::string& a = lines[keyed[rng() % keyed.size()]];
    std::string& b = lines[keyed[rng() % keyed.size()]];
    const std::size_t ea = a.find(" = "), eb = b.find(" = ");
    switch (rng() % 4) {
      case 0:
      case 1:
        a = a.substr(0, ea) + " = " + kValues[rng() % kValues.size()];
        break;
      case 2: {  // values swapped
        const std::string va = a.substr(ea), vb = b.substr(eb);
        a = a.substr(0, ea) + vb, b = b.substr(0, eb) + va;
        break;
      }
      default: {  // keys swapped
        const std::string ka = a.substr(0, ea), kb = b.substr(0, eb);
        a = kb + a.substr(ea), b = ka + b.substr(eb);
        break;
      }
    }
  }
  return join_lines(lines);
}

// A .msh (ASCII): in $Nodes a coordinate made NaN or huge, in $Elements a node tag made 0,
// negative, one past the last node or 2^31; or a section header swapped with another.
std::string mutate_msh_structure(const std::string& original, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<std::string> lines = split_lines(original);
  std::size_t nodes_at = 0, elements_at = 0, end_nodes = 0, end_elements = 0;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (lines[i] == "$Nodes") nodes_at = i;
    if (lines[i] == "$EndNodes") end_nodes = i;
    if (lines[i] == "$Elements") elements_at = i;
    if (lines[i] == "$EndElements") end_elements = i;
  }
  const auto words = [](const std::string& l) {
    std::vector<std::string> w;
    std::stringstream s(l);
    for (std::string x; s >> x;) w.push_back(x);
    return w;
  };
  const auto join = [](const std::vector<std::string>& w) {
    std::string l;
    for (const auto& x : w) l += (l.empty() ? "" : " ") + x;
    return l;
  };
  const int rounds = 1 + static_cast<int>(rng() % 3);
  for (int r = 0; r < rounds; ++r) {
    const int op = static_cast<int>(rng() % 3);
    if (op == 0 && end_nodes > nodes_at + 2) {
      const std::size_t i = nodes_at + 2 + rng() % (end_nodes - nodes_at - 2);
      std::vector<std::string> w = words(lines[i]);
      static const char* values[] = {"nan", "inf", "1e300", "-1e300", "1e10"};
      if (w.size() == 3) w[rng() % 3] = values[rng() % std::size(values)];
      lines[i] = join(w);
    } else if (op == 1 && end_elements > elements_at + 2) {
      const std::size_t i = elements_at + 2 + rng() % (end_elements - elements_at - 2);
      std::vector<std::string> w = words(lines[i]);
      static const char* values[] = {"0", "-1", "28", "2147483648", "99999"};
      if (w.size() > 1) w[1 + rng() % (w.size() - 1)] = values[rng() % std::size(values)];
      lines[i] = join(w);
    } else if (!lines.empty()) {
      std::swap(lines[rng() % lines.size()], lines[rng() % lines.size()]);
    }
  }
  return join_lines(lines);
}

std::vector<Target> make_targets(const fs::path& work) {
  std::vector<Target> t;
  fs::create_directories(work);
  {  // scenario: read and build (meshes, placement, materials, boundaries, contact surfaces)
    const fs::path d = work / "scenario";
    fs::create_directories(d);
    write_msh(d / "pad.msh", samples::make_box_mesh(2, 2, 2, 0.01, 0.01, 0.01));
    write_msh(d / "base.msh", samples::make_box_mesh(2, 2, 1, 0.01, 0.01, 0.01));
    write_file(d / "s.toml", kScenario);
    t.push_back({"scenario", d / "s.toml", true, [d] { solver::build_model(solver::read_scenario(d / "s.toml")); }});
  }
  for (bool binary : {false, true}) {  // .msh, both encodings
    const fs::path d = work / (binary ? "msh_binary" : "msh_ascii");
    fs::create_directories(d);
    TetMesh m = samples::make_box_mesh(2, 2, 1, 0.02, 0.02, 0.01);
    samples::perturb_interior_nodes(m, 0.01, 0.2, 3);
    write_msh(d / "m.msh", m, binary);
    t.push_back({d.filename().string(), d / "m.msh", !binary, [d] { read_msh(d / "m.msh"); }});
  }
  {  // slice stack: stack.json and one PNG slice
    samples::PhantomParams p;
    p.voxel_mm = p.slice_mm = 8.0;
    const fs::path d = work / "stack";
    samples::write_slice_stack(samples::make_hand_phantom(p).ct, d);
    t.push_back({"stack_json", d / "stack.json", true, [d] { segment::read_slice_stack(d); }});
    fs::path slice;
    for (const auto& e : fs::directory_iterator(d))
      if (e.path().extension() == ".png") slice = std::max(slice, e.path());
    Target png{"png", slice, false, [d] { segment::read_slice_stack(d); }};
    png.fixup = fix_png_crcs;
    t.push_back(png);
    // DICOM: one file of a series mutated (tactus's element walk, then GDCM's decoder), plain and RLE.
    for (const char* compression : {"none", "rle"}) {
      const fs::path dd = work / (std::string("dicom_") + compression);
      samples::DicomSeriesOptions o;
      o.compression = compression;
      samples::write_dicom_series(samples::make_hand_phantom(p).ct, dd, o);
      t.push_back({"dicom_" + std::string(compression), dd / "IM_0005.dcm", false, [dd] { segment::read_dicom_series(dd); }});
    }
    // NIfTI, NRRD, MetaImage and INRIMAGE headers and voxels, written by hand from the same phantom.
    const Volume<std::int16_t> ct = samples::make_hand_phantom(p).ct;
    const std::string voxels(reinterpret_cast<const char*>(ct.data.data()), ct.data.size() * sizeof(std::int16_t));
    const fs::path dv = work / "volumes";
    fs::create_directories(dv);
    const std::string sizes = std::to_string(ct.dims[0]) + " " + std::to_string(ct.dims[1]) + " " + std::to_string(ct.dims[2]);
    write_file(dv / "ct.nrrd", "NRRD0004\ntype: short\ndimension: 3\nspace: left-posterior-superior\nsizes: " + sizes +
                                   "\nspace directions: (8,0,0) (0,8,0) (0,0,8)\nendian: little\nencoding: raw\nspace origin: (1,2,3)\n\n" + voxels);
    t.push_back({"nrrd", dv / "ct.nrrd", true, [dv] { segment::read_volume_file(dv / "ct.nrrd"); }});
    write_file(dv / "ct.mha", "ObjectType = Image\nNDims = 3\nDimSize = " + sizes +
                                  "\nElementType = MET_SHORT\nElementSpacing = 8 8 8\nOffset = 1 2 3\nTransformMatrix = 0 1 0 -1 0 0 0 0 1\n"
                                  "ElementDataFile = LOCAL\n" +
                                  voxels);
    t.push_back({"metaimage", dv / "ct.mha", true, [dv] { segment::read_volume_file(dv / "ct.mha"); }});
    {  // INRIMAGE-4: the header padded with newlines to 256 bytes, closed by "##}"
      std::string inr = "#INRIMAGE-4#{\nXDIM=" + std::to_string(ct.dims[0]) + "\nYDIM=" + std::to_string(ct.dims[1]) +
                        "\nZDIM=" + std::to_string(ct.dims[2]) +
                        "\nVDIM=1\nTYPE=signed fixed\nPIXSIZE=16 bits\nSCALE=2**0\nCPU=decm\nVX=8\nVY=8\nVZ=8\nXO=1\nYO=2\nZO=3\n";
      inr += std::string(256 - 4 - inr.size(), '\n') + "##}\n";
      write_file(dv / "ct.inr", inr + voxels);
      t.push_back({"inrimage", dv / "ct.inr", true, [dv] { segment::read_volume_file(dv / "ct.inr"); }});
    }
    std::string nifti(352, '\0');
    auto put = [&](std::size_t off, const auto& v) { std::memcpy(nifti.data() + off, &v, sizeof v); };
    put(0, std::int32_t{348});
    const std::int16_t dim[8] = {
        3, static_cast<std::int16_t>(ct.dims[0]), static_cast<std::int16_t>(ct.dims[1]), static_cast<std::int16_t>(ct.dims[2]), 1, 1, 1, 1};
    std::memcpy(nifti.data() + 40, dim, sizeof dim);
    put(70, std::int16_t{4}), put(72, std::int16_t{16});
    const float pixdim[4] = {1, 8, 8, 8};
    std::memcpy(nifti.data() + 76, pixdim, sizeof pixdim);
    put(108, 352.0f), put(112, 1.0f), put(116, 0.0f);
    nifti[123] = 2;  // mm
    put(252, std::int16_t{1}), put(256, 0.0f), put(260, 0.0f), put(264, 0.7071068f), put(268, 1.0f), put(272, 2.0f), put(276, 3.0f);
    std::memcpy(nifti.data() + 344, "n+1\0", 4);
    write_file(dv / "ct.nii", nifti + voxels);
    t.push_back({"nifti", dv / "ct.nii", false, [dv] { segment::read_volume_file(dv / "ct.nii"); }});
  }
  {  // labels.h5
    Volume<std::uint8_t> v({6, 5, 4}, {1e-3, 1e-3, 2e-3}, {0, 0, 0});
    for (std::size_t i = 0; i < v.size(); ++i) v.data[i] = static_cast<std::uint8_t>(i % 3);
    LabelTable table{{0, "background"}, {1, "soft_tissue"}, {2, "bone_02"}};
    const fs::path d = work / "labels";
    write_h5(d / "labels.h5", "/labels", v, &table);
    t.push_back({"labels_h5", d / "labels.h5", false, [d] {
                   LabelTable lt;
                   read_h5<std::uint8_t>(d / "labels.h5", "/labels", &lt);
                 }});
  }
  {  // a partition (tactus-solve decompose --partition): METIS's own for a small box model
    solver::MaterialValues v;
    v.numbers = {{"E", 1e6}, {"nu", 0.3}, {"density", 1000.0}};
    auto model = std::make_shared<solver::Model>(
        solver::build_model(samples::make_box_mesh(8, 8, 4, 0.08, 0.08, 0.04), solver::Material::make("linear_elastic", v)));
    const fs::path f = work / "partition" / "partition.json";
    fs::create_directories(f.parent_path());
    write_file(f, solver::decomposition_json(solver::decompose(*model, 3, 16)).dump(1));
    t.push_back({"partition", f, true, [f, model] { solver::read_partition(*model, f); }});
  }
  {  // a restart checkpoint (core/state_file.hpp, as tactus-solve writes them)
    StateArrays state;
    state.kind = "tactus-solve checkpoint";
    for (int i = 0; i < 200; ++i) state.reals["integrator.u"].push_back(1e-4 * i), state.integers["contact.pair0.candidates"].push_back(i % 17);
    state.records["run.scenario"] = "/cases/s.toml";
    const fs::path f = work / "checkpoint" / "checkpoint_000000000100.h5";
    fs::create_directories(f.parent_path());
    write_state_file(f, state);
    t.push_back({"checkpoint", f, false, [f] { read_state_file(f, "tactus-solve checkpoint"); }});
  }
  {  // a checkpoint's values: a real run killed mid-contact, one array value changed and the
     // checksum written again (so only tactus's own validation stands between it and the solver),
     // then continued as tactus-solve --restart does. The restore runs to the end time.
    const fs::path d = work / "restart";
    fs::create_directories(d);
    write_msh(d / "pad.msh", samples::make_box_mesh(2, 2, 2, 0.01, 0.01, 0.01));
    write_msh(d / "base.msh", samples::make_box_mesh(2, 2, 1, 0.01, 0.01, 0.01));
    std::string sc = kScenario;
    sc.replace(sc.find("[run]\n"), 6, "[run]\ncheckpoint_interval = 1e-4\n");
    write_file(d / "s.toml", sc);
    const pid_t child = fork();
    if (child == 0) {  // killed at step 400 of ~500: the newest checkpoint is mid-contact
      setenv("TACTUS_KILL_AT", "step:400", 1);
      try {
        solver::run_simulation(solver::read_scenario(d / "s.toml"), d / "out");
      } catch (...) {
      }
      _exit(3);
    }
    int status = 0;
    waitpid(child, &status, 0);
    const std::optional<solver::RestartPoint> point = solver::find_restart_point(d / "out");
    if (!point) throw std::runtime_error("tactus-fuzz: the killed run left no checkpoint (setup)");
    for (const auto& e : fs::directory_iterator(point->file.parent_path()))  // only the one mutated: no fallback hides a refusal
      if (e.path() != point->file) fs::remove(e.path());
    const fs::path staging = point->staging, checkpoint = point->file;
    Target values{"checkpoint_values", checkpoint, false, [d, staging, checkpoint] {
                    // A private copy: a restore that is accepted publishes its output.
                    const fs::path own = d / ("run-" + std::to_string(getpid()));
                    fs::create_directories(own);
                    fs::copy(staging, own / staging.filename(), fs::copy_options::recursive);
                    const std::optional<solver::RestartPoint> from = solver::find_restart_point(own / "out");
                    if (!from) throw InputError(checkpoint.string(), "", "a checkpoint", "none read back");
                    const solver::Scenario scenario = solver::read_scenario(from->identity.scenario);
                    OutputFolder out(own / "out", {"tactus-solve", {}, false}, from->staging);
                    solver::run_simulation(scenario, out, solver::run_identity(scenario, {}), &*from);
                  }};
    values.mutator = [](const std::string& original, std::uint64_t seed) { return mutate_checkpoint_values(original, seed); };
    t.push_back(values);
  }
  {  // the structure of a scenario and a mesh: keys swapped, values of the wrong type, NaN, huge or
     // negative numbers, node indices out of range
    const fs::path d = work / "structured";
    fs::create_directories(d);
    write_msh(d / "pad.msh", samples::make_box_mesh(2, 2, 2, 0.01, 0.01, 0.01));
    write_msh(d / "base.msh", samples::make_box_mesh(2, 2, 1, 0.01, 0.01, 0.01));
    std::string sc = kScenario;
    sc.replace(sc.find("end_time = 1e-3"), 15, "end_time = 2e-5");
    sc.replace(sc.find("output_times = [5e-4, 1e-3]"), 27, "output_times = [2e-5]");
    write_file(d / "s.toml", sc);
    // A mutated but valid scenario may ask for a long run (end_time 1.7 s: 10^5 steps): the
    // harness gives every run the runaway guard a user with little time would set, so such a run
    // is refused up front by run.max_steps instead of running past the time limit.
    // (The same for a mutated mesh: a tiny element means many steps.)
    const auto run_capped = [d] {
      solver::Scenario s = solver::read_scenario(d / "s.toml");
      s.run.max_steps = std::min(s.run.max_steps, 20000.0);
      solver::run_simulation(s, d / ("out-" + std::to_string(getpid())));
    };
    Target scenario{"scenario_struct", d / "s.toml", true, run_capped};
    scenario.mutator = mutate_toml_structure;
    t.push_back(scenario);
    Target mesh{"msh_struct", d / "pad.msh", true, run_capped};
    mesh.mutator = mutate_msh_structure;
    t.push_back(mesh);
  }
  {  // a results folder: run.json, history.csv, a state .vtu
    const fs::path d = work / "results";
    fs::create_directories(d);
    write_msh(d / "cube.msh", samples::make_box_mesh(2, 2, 2, 0.01, 0.01, 0.01));
    write_file(d / "s.toml", R"([run]
end_time = 2e-4
[[bodies]]
name = "cube"
mesh = "cube.msh"
materials = { "*" = "m" }
initial_velocity = [1.0, 0, 0]
[materials.m]
type = "neo_hookean"
mu = 1e5
bulk = 1e6
density = 1000
)");
    log::set_level(log::Level::quiet);
    solver::run_simulation(solver::read_scenario(d / "s.toml"), d / "out");
    fs::remove(d / "out" / ".tactus-output.json");  // mutated files are read, never replaced
    const fs::path out = d / "out";
    auto report = [out] { postproc::summarize(postproc::read_results(out)); };
    t.push_back({"run_json", out / "run.json", true, report});
    t.push_back({"history_csv", out / "history.csv", true, report});
    t.push_back({"vtu", out / "results" / "state_0000.vtu", true, [out] { read_vtu(out / "results" / "state_0000.vtu"); }});
  }
  return t;
}

// --------------------------------------------------------------------------------------------
// Mutations.
const std::vector<std::string> kNumbers = {
    "0",  "-1", "1e308", "-1e308", "nan", "inf", "-inf", "1e-308", "1e30", "99999999999", "-2147483649", "4294967296", "18446744073709551616",
    "-0", "2.5"};

std::string mutate(std::string s, bool text, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  auto pick = [&](std::size_t n) { return n == 0 ? std::size_t{0} : static_cast<std::size_t>(rng() % n); };
  const int rounds = 1 + static_cast<int>(rng() % 3);
  for (int r = 0; r < rounds; ++r) {
    const int op = static_cast<int>(rng() % (text ? 10 : 6));
    const std::size_t n = s.size();
    switch (op) {
      case 0:  // flip bits
        for (int k = 0, m = 1 + static_cast<int>(rng() % 8); k < m && n; ++k) s[pick(n)] ^= static_cast<char>(1 << (rng() % 8));
        break;
      case 1: {  // interesting bytes
        static const char bytes[] = {'\0', '\xff', '\x7f', '\x80', '-', '9', ' ', '\n', '"', '$', '[', '{', '}', ','};
        for (int k = 0, m = 1 + static_cast<int>(rng() % 4); k < m && n; ++k) s[pick(n)] = bytes[pick(sizeof bytes)];
        break;
      }
      case 2: {  // delete a run
        const std::size_t at = pick(n), len = std::min<std::size_t>(1 + pick(64), n - at);
        s.erase(at, len);
        break;
      }
      case 3: {  // insert random bytes
        std::string ins(1 + pick(64), '\0');
        for (char& c : ins) c = static_cast<char>(rng());
        s.insert(pick(n + 1), ins);
        break;
      }
      case 4: {  // duplicate a chunk elsewhere
        if (!n) break;
        const std::size_t at = pick(n), len = std::min<std::size_t>(1 + pick(256), n - at);
        s.insert(pick(n + 1), s.substr(at, len));
        break;
      }
      case 5:  // truncate
        s.resize(pick(n + 1));
        break;
      case 6:
      case 7: {  // replace a number with an interesting one
        std::vector<std::pair<std::size_t, std::size_t>> numbers;
        for (std::size_t i = 0; i < n;) {
          if (std::isdigit(static_cast<unsigned char>(s[i]))) {
            std::size_t j = i;
            while (j < n && (std::isdigit(static_cast<unsigned char>(s[j])) || s[j] == '.' || s[j] == 'e' || s[j] == '-' || s[j] == '+')) ++j;
            numbers.emplace_back(i, j - i);
            i = j;
          } else {
            ++i;
          }
        }
        if (numbers.empty()) break;
        const auto [at, len] = numbers[pick(numbers.size())];
        s.replace(at, len, kNumbers[pick(kNumbers.size())]);
        break;
      }
      case 8:
      case 9: {  // duplicate or drop a line
        std::vector<std::size_t> starts{0};
        for (std::size_t i = 0; i < n; ++i)
          if (s[i] == '\n' && i + 1 < n) starts.push_back(i + 1);
        const std::size_t k = pick(starts.size());
        const std::size_t begin = starts[k], end = k + 1 < starts.size() ? starts[k + 1] : n;
        const std::string line = s.substr(begin, end - begin);
        if (op == 8)
          s.insert(begin, line);
        else
          s.erase(begin, end - begin);
        break;
      }
      default:
        break;
    }
  }
  return s;
}

// --------------------------------------------------------------------------------------------
enum class Outcome { accepted, refused, crash, hang, internal };
const char* outcome_name(Outcome o) {
  switch (o) {
    case Outcome::accepted:
      return "accepted";
    case Outcome::refused:
      return "refused";
    case Outcome::crash:
      return "CRASH";
    case Outcome::hang:
      return "HANG";
    case Outcome::internal:
      return "INTERNAL ERROR";
  }
  return "";
}

struct Limits {
  unsigned seconds = 60;  // above the readers' own limits (10 s + 1 s/MB for these small files)
  std::uint64_t memory = std::uint64_t{4} << 30;
};

// Reads in a child: exit 0 accepted, 10 refused (tactus error), 20 internal (other exception).
Outcome read_in_child(const Target& t, const Limits& lim, std::string& detail) {
  int fds[2];
  if (pipe(fds) != 0) return Outcome::internal;
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    alarm(lim.seconds);
#if !defined(__SANITIZE_ADDRESS__)
    rlimit r{static_cast<rlim_t>(lim.memory), static_cast<rlim_t>(lim.memory)};
    setrlimit(RLIMIT_AS, &r);
#endif
    int code = 0;
    std::string what;
    try {
      t.read();
    } catch (const tactus::Error& e) {
      code = 10, what = e.what();
    } catch (const std::exception& e) {
      code = 20, what = e.what();
    } catch (...) {
      code = 20, what = "unknown exception";
    }
    if (::write(fds[1], what.data(), std::min<std::size_t>(what.size(), 4000)) < 0) code = 30;
    _exit(code);
  }
  close(fds[1]);
  char buf[4096];
  const ssize_t got = read(fds[0], buf, sizeof buf);
  detail.assign(buf, got > 0 ? static_cast<std::size_t>(got) : 0);
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (WIFSIGNALED(status)) {
    detail = std::string("signal ") + strsignal(WTERMSIG(status));
    return WTERMSIG(status) == SIGALRM ? Outcome::hang : Outcome::crash;
  }
  switch (WEXITSTATUS(status)) {
    case 0:
      return Outcome::accepted;
    case 10:
      return Outcome::refused;
    default:
      return Outcome::internal;
  }
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string x; std::getline(ss, x, sep);)
    if (!x.empty()) out.push_back(x);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  std::string readers, save;
  long mutations = 100;
  std::uint64_t seed = 1;
  std::string replay_reader;
  std::vector<std::string> replay_files;
  for (std::size_t i = 0; i < args.size(); ++i) {
    auto next = [&] {
      if (i + 1 >= args.size()) {
        std::fprintf(stderr, "tactus-fuzz: %s needs a value\n", args[i].c_str());
        std::exit(2);
      }
      return args[++i];
    };
    if (args[i] == "--readers")
      readers = next();
    else if (args[i] == "--mutations")
      mutations = std::stol(next());
    else if (args[i] == "--seed")
      seed = std::stoull(next());
    else if (args[i] == "--save")
      save = next();
    else if (args[i] == "--replay") {
      replay_reader = next();
      while (i + 1 < args.size()) replay_files.push_back(args[++i]);
    } else {
      std::fprintf(stderr, "usage: tactus-fuzz [--readers a,b] [--mutations N] [--seed S] [--save DIR] | --replay READER FILE...\n");
      return 2;
    }
  }
  log::set_level(log::Level::quiet);
  const fs::path work = fs::temp_directory_path() / ("tactus-fuzz-" + std::to_string(getpid()));
  std::vector<Target> targets = make_targets(work);
  const std::vector<std::string> wanted = split(replay_reader.empty() ? readers : replay_reader, ',');
  Limits lim;
  int failures = 0;
  std::printf("%-12s %9s %9s %9s %6s %6s %9s %8s\n", "reader", "inputs", "accepted", "refused", "crash", "hang", "internal", "seconds");
  for (const Target& t : targets) {
    if (!wanted.empty() && std::find(wanted.begin(), wanted.end(), t.name) == wanted.end()) continue;
    const std::string original = read_file(t.file);
    std::map<Outcome, long> count;
    const auto t0 = std::chrono::steady_clock::now();
    const long n = replay_reader.empty() ? mutations : static_cast<long>(replay_files.size());
    for (long k = 0; k < n; ++k) {
      const std::uint64_t case_seed = seed * 1000003ULL + static_cast<std::uint64_t>(k);
      const std::string input = !replay_reader.empty() ? read_file(replay_files[static_cast<std::size_t>(k)])
                                : t.mutator            ? t.mutator(original, case_seed)
                                                       : t.fixup(mutate(original, t.text, case_seed));
      write_file(t.file, input);
      std::string detail;
      const Outcome o = read_in_child(t, lim, detail);
      ++count[o];
      if (o == Outcome::crash || o == Outcome::hang || o == Outcome::internal) {
        ++failures;
        std::string where = replay_reader.empty() ? "mutation " + std::to_string(k) : replay_files[static_cast<std::size_t>(k)];
        if (!save.empty() && replay_reader.empty()) {
          fs::create_directories(fs::path(save) / t.name);
          const fs::path keep = fs::path(save) / t.name / ("seed" + std::to_string(seed) + "-" + std::to_string(k) + t.file.extension().string());
          write_file(keep, input);
          where += " (saved as " + keep.string() + ")";
        }
        std::printf("  %s: %s on %s: %s\n", t.name.c_str(), outcome_name(o), where.c_str(), detail.substr(0, 300).c_str());
      }
    }
    write_file(t.file, original);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%-12s %9ld %9ld %9ld %6ld %6ld %9ld %8.1f\n", t.name.c_str(), n, count[Outcome::accepted], count[Outcome::refused],
                count[Outcome::crash], count[Outcome::hang], count[Outcome::internal], seconds);
    std::fflush(stdout);
  }
  std::error_code ec;
  fs::remove_all(work, ec);
  std::printf(failures ? "tactus-fuzz: %d failing inputs\n" : "tactus-fuzz: no crash, hang or internal error\n", failures);
  return failures ? 1 : 0;
}
