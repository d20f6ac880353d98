// segment/volume_files: NIfTI, NRRD and MetaImage CT volumes. Oracle: files written by
// independent writers (nibabel for NIfTI with an sform and with a reflected qform, VTK's
// vtkMetaImageWriter raw and zlib, hand-written ITK-layout .mha and NRRD headers in RAS and LPS)
// and what they hold: every voxel HU = slope * v + intercept with v = (7 i + 13 j + 29 k) % 500 -
// 250, and the spacing, origin and direction in the LPS world frame (tests/segment/
// volume_files.py computes them from the affines it wrote). Truncated and corrupt files stop with
// one InputError naming the file.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>

#include "expect_error.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/volume.hpp"
#include "tactus/segment/run.hpp"
#include "tactus/segment/volume_files.hpp"
#include "temp_dir.hpp"

using namespace tactus;
namespace fs = std::filesystem;

namespace {

fs::path written_files(const testkit::TempDir& dir) {
  // Debian's interpreter, which python3-nibabel and python3-vtk9 install into.
  const std::string command = "/usr/bin/python3 " TACTUS_SOURCE_DIR "/tests/segment/volume_files.py '" + (dir / "v").string() + "'";
  EXPECT_EQ(std::system(command.c_str()), 0) << command << " (needs Debian's python3-nibabel, python3-vtk9, python3-numpy)";
  return dir / "v";
}

}  // namespace

TEST(VolumeFiles, IndependentlyWrittenFilesReadToTheirValuesAndGeometry) {
  testkit::TempDir dir;
  const fs::path folder = written_files(dir);
  std::ifstream in(folder / "expected.json");
  const nlohmann::json expected = nlohmann::json::parse(in);
  ASSERT_EQ(expected.size(), 7u);
  for (const auto& [name, e] : expected.items()) {
    ASSERT_TRUE(segment::is_volume_file(folder / name));
    const segment::SliceStack s = segment::read_volume_file(folder / name);
    ASSERT_EQ(s.hu.dims, (std::array<int, 3>{9, 7, 6})) << name;
    double hu = 0, direction = 0, spacing = 0, origin = 0;
    const double slope = e["slope"], intercept = e["intercept"];
    for (int k = 0; k < 6; ++k)
      for (int j = 0; j < 7; ++j)
        for (int i = 0; i < 9; ++i) hu = std::max(hu, std::abs(s.hu.at(i, j, k) - (slope * ((7 * i + 13 * j + 29 * k) % 500 - 250) + intercept)));
    for (int c = 0; c < 9; ++c)
      direction =
          std::max(direction, std::abs(s.hu.direction[static_cast<std::size_t>(c)] - e["direction"][static_cast<std::size_t>(c)].get<double>()));
    for (int a = 0; a < 3; ++a) {
      spacing = std::max(spacing, std::abs(s.hu.spacing[static_cast<std::size_t>(a)] - e["spacing"][static_cast<std::size_t>(a)].get<double>()));
      origin = std::max(origin, std::abs(s.hu.origin[static_cast<std::size_t>(a)] - e["origin"][static_cast<std::size_t>(a)].get<double>()));
    }
    std::printf("%-13s (%s): largest HU error %g, direction %.1e, spacing %.1e m, origin %.1e m, det %+.0f\n", name.c_str(),
                s.source.substr(0, s.source.find(' ')).c_str(), hu, direction, spacing, origin, determinant(s.hu.direction));
    EXPECT_EQ(hu, 0.0) << name;
    EXPECT_LE(direction, 1e-6) << name;  // NIfTI stores float32
    EXPECT_LE(spacing, 1e-9) << name;
    EXPECT_LE(origin, 1e-8) << name;
  }
}

TEST(VolumeFiles, TruncatedAndCorruptFilesAreNamed) {
  testkit::TempDir dir;
  const fs::path folder = written_files(dir);
  // Cuts the last bytes off `damaged` (the file itself, or its detached data), then reads `name`.
  auto cut = [&](const char* name, const char* damaged, std::size_t keep_from_end) {
    const fs::path p = folder / damaged;
    std::string b;
    {
      std::ifstream in(p, std::ios::binary);
      b.assign((std::istreambuf_iterator<char>(in)), {});
    }
    std::ofstream(p, std::ios::binary | std::ios::trunc) << b.substr(0, b.size() - keep_from_end);
    return testkit::input_error_of([&] { segment::read_volume_file(folder / name); });
  };
  for (const char* name : {"sform.nii", "qform.nii.gz", "ras.nrrd", "rotated.mha", "vtk_zlib.mhd"}) {
    const std::string m = cut(name, std::string(name) == "vtk_zlib.mhd" ? "vtk_zlib.zraw" : name, 20);
    std::printf("%s cut short: %s\n", name, m.c_str());
    EXPECT_NE(m.find(name), std::string::npos);
    EXPECT_TRUE(m.find("truncated") != std::string::npos || m.find("corrupt") != std::string::npos) << m;
  }
  {  // a sheared affine
    std::ofstream(folder / "shear.nrrd") << "NRRD0004\ntype: short\ndimension: 3\nspace: LPS\nsizes: 2 2 2\n"
                                            "space directions: (1,0,0) (0.5,1,0) (0,0,1)\nendian: little\nencoding: raw\n\n"
                                         << std::string(16, '\0');
    const std::string m = testkit::input_error_of([&] { segment::read_volume_file(folder / "shear.nrrd"); });
    std::printf("sheared: %s\n", m.c_str());
    EXPECT_NE(m.find("sheared"), std::string::npos);
  }
  {  // a multi-channel MetaImage
    std::ofstream(folder / "rgb.mha") << "NDims = 3\nDimSize = 2 2 2\nElementType = MET_UCHAR\nElementNumberOfChannels = 3\n"
                                         "ElementSpacing = 1 1 1\nElementDataFile = LOCAL\n"
                                      << std::string(24, '\0');
    const std::string m = testkit::input_error_of([&] { segment::read_volume_file(folder / "rgb.mha"); });
    std::printf("channels: %s\n", m.c_str());
    EXPECT_NE(m.find("ElementNumberOfChannels"), std::string::npos);
  }
}

namespace {
// An INRIMAGE-4 file of 5 x 4 x 3 voxels, value (i + 2 j + 7 k) * scale, written by hand to the
// format's definition: a 256-byte header, then the voxels x fastest.
void write_inr(const fs::path& file, const std::string& type, int bits, const std::string& cpu, int scale) {
  std::string head = "#INRIMAGE-4#{\nXDIM=5\nYDIM=4\nZDIM=3\nVDIM=1\nTYPE=" + type + "\nPIXSIZE=" + std::to_string(bits) +
                     " bits\nSCALE=2**0\nCPU=" + cpu + "\nVX=0.5\nVY=0.75\nVZ=2\nXO=10\n#GEOMETRY=CARTESIAN\n";
  head += std::string(256 - 4 - head.size(), '\n') + "##}\n";
  std::ofstream out(file, std::ios::binary);
  out << head;
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 5; ++i) {
        const unsigned v = static_cast<unsigned>((i + 2 * j + 7 * k) * scale);
        const float f = static_cast<float>(v);
        if (bits == 8)
          out.put(static_cast<char>(v));
        else if (bits == 32)
          out.write(reinterpret_cast<const char*>(&f), 4);
        else if (cpu == "sun")
          out.put(static_cast<char>(v >> 8)), out.put(static_cast<char>(v & 255));
        else
          out.put(static_cast<char>(v & 255)), out.put(static_cast<char>(v >> 8));
      }
}
}  // namespace

TEST(VolumeFiles, InrimageReadsToItsValuesSpacingAndOrigin) {
  testkit::TempDir dir;
  write_inr(dir / "a.inr", "unsigned fixed", 8, "decm", 1);
  write_inr(dir / "b.inr", "unsigned fixed", 16, "sun", 100);
  ASSERT_EQ(std::system(("gzip -k '" + (dir / "b.inr").string() + "'").c_str()), 0);
  for (const char* name : {"a.inr", "b.inr", "b.inr.gz"}) {
    ASSERT_TRUE(segment::is_volume_file(dir / name));
    const segment::SliceStack s = segment::read_volume_file(dir / name);
    const int scale = name[0] == 'a' ? 1 : 100;
    double worst = 0;
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 5; ++i) worst = std::max(worst, std::abs(static_cast<double>(s.hu.at(i, j, k)) - (i + 2 * j + 7 * k) * scale));
    std::printf("  %s: dims %d %d %d, spacing %g %g %g m, origin x %g m, largest value error %g\n", name, s.hu.dims[0], s.hu.dims[1], s.hu.dims[2],
                s.hu.spacing[0], s.hu.spacing[1], s.hu.spacing[2], s.hu.origin[0], worst);
    EXPECT_EQ(s.hu.dims, (std::array<int, 3>{5, 4, 3}));
    EXPECT_NEAR(s.hu.spacing[0], 0.5e-3, 1e-15);
    EXPECT_NEAR(s.hu.spacing[1], 0.75e-3, 1e-15);
    EXPECT_NEAR(s.hu.spacing[2], 2e-3, 1e-15);
    EXPECT_NEAR(s.hu.origin[0], 10e-3, 1e-15);
    EXPECT_EQ(worst, 0);
  }
  // A truncated file and an unknown voxel type stop with the file and field named.
  std::string bytes;
  {
    std::ifstream in(dir / "a.inr", std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  std::ofstream(dir / "short.inr", std::ios::binary) << bytes.substr(0, bytes.size() - 7);
  testkit::expect_input_error([&] { segment::read_volume_file(dir / "short.inr"); }, {"short.inr", "voxels", "truncated"});
  write_inr(dir / "c.inr", "complex", 8, "decm", 1);
  testkit::expect_input_error([&] { segment::read_volume_file(dir / "c.inr"); }, {"c.inr", "TYPE/PIXSIZE", "complex"});
}

TEST(VolumeFiles, ImportedLabelVolumeKeepsItsRegionsRenumbered) {
  testkit::TempDir dir;
  write_inr(dir / "labels.inr", "unsigned fixed", 8, "pc", 1);  // values 0..24: 24 labels and background
  segment::StageOptions o;
  o.import_labels = true;
  o.write_surfaces = false;
  o.labels.tissue_value = 20;
  o.labels.names[24] = "vessel";
  const nlohmann::json j = segment::run_segment_stage(dir / "labels.inr", dir / "out", o);
  const auto imported = j["imported_labels"];
  ASSERT_EQ(imported.size(), 25u);
  LabelTable table;
  const auto labels = read_h5<std::uint8_t>(dir / "out" / "labels.h5", "/labels", &table);
  // 20 -> 1; the others in increasing order from 2: value v < 20 -> v + 1, v > 20 -> v.
  std::size_t wrong = 0;
  for (int k = 0; k < 3; ++k)
    for (int j2 = 0; j2 < 4; ++j2)
      for (int i = 0; i < 5; ++i) {
        const int v = i + 2 * j2 + 7 * k;
        wrong += labels.at(i, j2, k) != (v == 0 ? 0 : v == 20 ? 1 : v < 20 ? v + 1 : v);
      }
  std::printf("  %zu imported labels, %zu voxels with a wrong label, value 24 named '%s'\n", imported.size() - 1, wrong, table.at(24).c_str());
  EXPECT_EQ(wrong, 0u);
  EXPECT_EQ(table.at(1), "soft_tissue");
  EXPECT_EQ(table.at(24), "vessel");
  EXPECT_EQ(table.at(2), "label_1");
  // A CT passed by mistake (fractions) is refused with the voxel named.
  write_inr(dir / "ct.inr", "float", 32, "decm", 1);
  {
    std::fstream f(dir / "ct.inr", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(256 + 4);
    const float x = 0.5f;
    f.write(reinterpret_cast<const char*>(&x), 4);
  }
  testkit::expect_input_error([&] { segment::run_segment_stage(dir / "ct.inr", dir / "out2", o); },
                              {"whole label numbers", "0.5 at voxel (1, 0, 0)"});
}
