// segment/volume_files: NIfTI, NRRD and MetaImage CT volumes. Oracle: files written by
// independent writers (nibabel for NIfTI with an sform and with a reflected qform, VTK's
// vtkMetaImageWriter raw and zlib, hand-written ITK-layout .mha and NRRD headers in RAS and LPS)
// and what they hold: every voxel HU = slope * v + intercept with v = (7 i + 13 j + 29 k) % 500 -
// 250, and the spacing, origin and direction in the LPS world frame (tests/segment/
// volume_files.py computes them from the affines it wrote). Truncated and corrupt files stop with
// one InputError naming the file.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>

#include "expect_error.hpp"
#include "tactus/core/error.hpp"
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
