// segment/dicom: the DICOM series reader. Oracles: the phantom's slice stack (the PNG path) for
// series tactus writes (uncompressed, RLE, JPEG lossless), an independently written series
// (pydicom: implicit VR, signed pixels, another rescale, nested sequences, random file names)
// against the analytic values it stores, and dciodvfy (dicom3tools) for what tactus writes.
// Malformed folders stop with one InputError naming the file and the element.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <functional>
#include <random>

#include "expect_error.hpp"
#include "tactus/core/error.hpp"
#include "tactus/data_samples/phantom.hpp"
#include "tactus/segment/dicom.hpp"
#include "tactus/segment/segment.hpp"
#include "tactus/segment/stack.hpp"
#include "temp_dir.hpp"

using namespace tactus;
namespace fs = std::filesystem;

namespace {

samples::Phantom small_phantom() {
  samples::PhantomParams p;
  p.voxel_mm = 2.0, p.slice_mm = 2.5;  // 86 x 47 x 96 voxels
  return samples::make_hand_phantom(p);
}

// The largest |a - b| over the voxels, or +inf when the grids differ.
double largest_difference(const Volume<float>& a, const Volume<float>& b) {
  if (a.dims != b.dims) return 1e300;
  for (int c = 0; c < 3; ++c)
    if (std::abs(a.spacing[c] - b.spacing[c]) > 1e-12 || std::abs(a.origin[c] - b.origin[c]) > 1e-12) return 1e300;
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, static_cast<double>(std::abs(a.data[i] - b.data[i])));
  return worst;
}

std::vector<fs::path> files_of(const fs::path& folder) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(folder)) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

// The phantom written as a slice stack and as DICOM series (three transfer syntaxes) reads back to
// the same Hounsfield values, grid and origin, and segments to the same labels.
TEST(Dicom, PhantomSeriesReadsLikeThePngStack) {
  testkit::TempDir dir;
  const samples::Phantom ph = small_phantom();
  samples::write_slice_stack(ph.ct, dir / "png");
  const segment::SliceStack png = segment::read_slice_stack(dir / "png");
  const segment::Segmentation reference = segment::segment_hand(png.hu, {});
  for (const char* compression : {"none", "rle", "jpeg-lossless"}) {
    samples::DicomSeriesOptions o;
    o.compression = compression;
    samples::write_dicom_series(ph.ct, dir / compression, o);
    const segment::SliceStack dcm = segment::read_dicom_series(dir / compression);
    const double difference = largest_difference(png.hu, dcm.hu);
    const segment::Segmentation s = segment::segment_hand(dcm.hu, {});
    std::size_t differing = s.labels.size() == reference.labels.size() ? 0 : s.labels.size();
    for (std::size_t i = 0; i < std::min(s.labels.size(), reference.labels.size()); ++i) differing += s.labels.data[i] != reference.labels.data[i];
    std::printf("DICOM (%s) vs PNG stack: %d x %d x %d voxels, largest HU difference %g, %zu labels differ of %zu, %zu bones (PNG %zu)\n",
                compression, dcm.hu.dims[0], dcm.hu.dims[1], dcm.hu.dims[2], difference, differing, s.labels.size(), s.bones.size(),
                reference.bones.size());
    EXPECT_EQ(difference, 0.0);
    EXPECT_EQ(differing, 0u);
    EXPECT_TRUE(segment::is_dicom_folder(dir / compression));
  }
  EXPECT_FALSE(segment::is_dicom_folder(dir / "png"));
}

// File names carry no order: shuffled and renamed files read to the same volume.
TEST(Dicom, ShuffledFileNamesReadTheSame) {
  testkit::TempDir dir;
  const samples::Phantom ph = small_phantom();
  samples::write_dicom_series(ph.ct, dir / "a");
  const segment::SliceStack a = segment::read_dicom_series(dir / "a");
  std::vector<fs::path> files = files_of(dir / "a");
  std::mt19937 rng(3);
  std::shuffle(files.begin(), files.end(), rng);
  fs::create_directories(dir / "b");
  for (std::size_t k = 0; k < files.size(); ++k) fs::copy_file(files[k], dir / "b" / ("x" + std::to_string(k)));
  const segment::SliceStack b = segment::read_dicom_series(dir / "b");
  std::printf("shuffled names: largest HU difference %g over %zu voxels\n", largest_difference(a.hu, b.hu), b.hu.size());
  EXPECT_EQ(largest_difference(a.hu, b.hu), 0.0);
}

// A slice taken out of the middle: the gap is twice the spacing, named with both neighbours.
TEST(Dicom, MissingSliceIsAnError) {
  testkit::TempDir dir;
  samples::write_dicom_series(small_phantom().ct, dir / "s");
  fs::remove(dir / "s" / "IM_0040.dcm");
  const std::string message = testkit::input_error_of([&] { segment::read_dicom_series(dir / "s"); });
  std::printf("%s\n", message.c_str());
  EXPECT_NE(message.find("IM_0041.dcm"), std::string::npos);
  EXPECT_NE(message.find("IM_0039.dcm"), std::string::npos);
  EXPECT_NE(message.find("missing slice"), std::string::npos);
}

// Two series in one folder: without a choice the error lists both; --series reads the one named.
TEST(Dicom, TwoSeriesAreListedAndOneIsChosen) {
  testkit::TempDir dir;
  const samples::Phantom ph = small_phantom();
  samples::DicomSeriesOptions first, second;
  first.series_uid = "1.2.826.0.1.3680043.10.1", first.description = "soft kernel";
  second.series_uid = "1.2.826.0.1.3680043.10.2", second.description = "bone kernel";
  Volume<std::int16_t> brighter = ph.ct;
  for (auto& v : brighter.data) v = static_cast<std::int16_t>(v + 10);
  samples::write_dicom_series(ph.ct, dir / "one", first);
  samples::write_dicom_series(brighter, dir / "two", second);
  fs::create_directories(dir / "both");
  for (const char* s : {"one", "two"})
    for (const auto& f : files_of(dir / s)) fs::copy_file(f, dir / "both" / (std::string(s) + "_" + f.filename().string()));
  const std::string message = testkit::input_error_of([&] { segment::read_dicom_series(dir / "both"); });
  std::printf("%s\n", message.c_str());
  EXPECT_NE(message.find(first.series_uid + " ('soft kernel', 96 images)"), std::string::npos);
  EXPECT_NE(message.find(second.series_uid + " ('bone kernel', 96 images)"), std::string::npos);
  const segment::SliceStack two = segment::read_dicom_series(dir / "both", second.series_uid);
  const segment::SliceStack alone = segment::read_dicom_series(dir / "two");
  EXPECT_EQ(largest_difference(two.hu, alone.hu), 0.0);
  EXPECT_NE(testkit::input_error_of([&] { segment::read_dicom_series(dir / "both", "1.2.3"); }).find("one of the folder's series"),
            std::string::npos);
}

// A series written by pydicom (implicit VR little endian, signed 12 of 16 bits with the upper 4
// set, slope 2, intercept -1000,
// PixelSpacing 0.8 \ 0.6, positions 1.25 mm apart while SliceThickness says 3, nested sequences of
// undefined length, random names written in random order, a text file and a pixel-less DICOM file
// beside them): every voxel equals 2 v - 1000 with v = (7 i + 13 j + 29 k) % 500 - 250.
TEST(Dicom, IndependentlyWrittenSeriesReadsToItsValues) {
  testkit::TempDir dir;
  // Debian's interpreter, which python3-pydicom installs into (not whatever python3 comes first on PATH).
  const std::string command = "/usr/bin/python3 " TACTUS_SOURCE_DIR "/tests/segment/pydicom_series.py '" + (dir / "py").string() + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << command << " (needs Debian's python3-pydicom)";
  const segment::SliceStack s = segment::read_dicom_series(dir / "py");
  ASSERT_EQ(s.hu.dims, (std::array<int, 3>{9, 7, 6}));
  double worst = 0;
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 7; ++j)
      for (int i = 0; i < 9; ++i) worst = std::max(worst, std::abs(s.hu.at(i, j, k) - (2.0 * ((7 * i + 13 * j + 29 * k) % 500 - 250) - 1000)));
  std::printf("pydicom series: %d x %d x %d, spacing %.4g %.4g %.4g mm, origin %.4g %.4g %.4g mm, largest HU error %g\n", s.hu.dims[0], s.hu.dims[1],
              s.hu.dims[2], s.hu.spacing[0] * 1e3, s.hu.spacing[1] * 1e3, s.hu.spacing[2] * 1e3, s.hu.origin[0] * 1e3, s.hu.origin[1] * 1e3,
              s.hu.origin[2] * 1e3, worst);
  EXPECT_EQ(worst, 0.0);
  EXPECT_NEAR(s.hu.spacing[0], 0.6e-3, 1e-12);  // x along the rows: the column spacing
  EXPECT_NEAR(s.hu.spacing[1], 0.8e-3, 1e-12);
  EXPECT_NEAR(s.hu.spacing[2], 1.25e-3, 1e-12);
  EXPECT_NEAR(s.hu.origin[0], 10e-3, 1e-12);
  EXPECT_NEAR(s.hu.origin[2], 30e-3, 1e-12);
}

// What tactus writes passes an independent validator (dciodvfy, dicom3tools) without an error.
TEST(Dicom, WrittenSeriesPassesDciodvfy) {
  testkit::TempDir dir;
  samples::PhantomParams p;
  p.voxel_mm = p.slice_mm = 6.0;
  samples::write_dicom_series(samples::make_hand_phantom(p).ct, dir / "s");
  for (const char* file : {"IM_0001.dcm", "IM_0010.dcm"}) {
    const std::string command = "dciodvfy '" + (dir / "s" / file).string() + "' 2>&1";
    FILE* pipe = popen(command.c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::string out;
    char buf[512];
    while (fgets(buf, sizeof buf, pipe)) out += buf;
    const int rc = pclose(pipe);
    std::printf("dciodvfy %s (exit %d): %s", file, rc, out.c_str());
    ASSERT_NE(out.find("CTImage"), std::string::npos) << "dciodvfy (Debian's dicom3tools) did not run";
    EXPECT_EQ(out.find("Error"), std::string::npos);
    EXPECT_EQ(out.find("Warning"), std::string::npos);
  }
}

// Truncated or corrupted files are named, with the element and byte where the walk stopped,
// before any decoder sees them.
TEST(Dicom, CorruptFilesAreNamedBeforeDecoding) {
  testkit::TempDir dir;
  samples::PhantomParams p;
  p.voxel_mm = p.slice_mm = 6.0;
  samples::write_dicom_series(samples::make_hand_phantom(p).ct, dir / "s");
  const fs::path victim = dir / "s" / "IM_0005.dcm";
  std::string bytes;
  {
    std::ifstream in(victim, std::ios::binary);
    bytes.assign((std::istreambuf_iterator<char>(in)), {});
  }
  auto write = [&](const std::string& b) { std::ofstream(victim, std::ios::binary | std::ios::trunc) << b; };
  write(bytes.substr(0, bytes.size() - 100));  // pixel data cut short
  std::string m = testkit::input_error_of([&] { segment::read_dicom_series(dir / "s"); });
  std::printf("truncated: %s\n", m.c_str());
  EXPECT_NE(m.find("IM_0005.dcm"), std::string::npos);
  EXPECT_NE(m.find("(7FE0,0010)"), std::string::npos);
  std::string broken = bytes;
  const std::size_t rows = broken.find(std::string("\x28\x00\x10\x00US", 6));
  ASSERT_NE(rows, std::string::npos);
  broken[rows + 6] = '\x7F', broken[rows + 7] = '\x7F';  // Rows' length: 32,639 bytes
  write(broken);
  m = testkit::input_error_of([&] { segment::read_dicom_series(dir / "s"); });
  std::printf("bad length: %s\n", m.c_str());
  EXPECT_NE(m.find("IM_0005.dcm"), std::string::npos);
  write(std::string(200, 'x'));  // not DICOM at all: left aside, and then a slice is missing
  m = testkit::input_error_of([&] { segment::read_dicom_series(dir / "s"); });
  std::printf("not DICOM: %s\n", m.c_str());
  EXPECT_NE(m.find("missing slice"), std::string::npos);
}

// A series whose rows run along -x and columns along -y (a prone patient) and one turned 30
// degrees about the slice axis: the voxels read back as written, and the orientation becomes the
// volume's direction (columns: row, column, slice normal), the first slice's position its origin.
TEST(Dicom, OrientationIsCarried) {
  testkit::TempDir dir;
  samples::PhantomParams p;
  p.voxel_mm = p.slice_mm = 5.0;
  const Volume<std::int16_t> ct = samples::make_hand_phantom(p).ct;
  const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
  for (const Direction& D : {Direction{-1, 0, 0, 0, -1, 0, 0, 0, 1}, Direction{c, -s, 0, s, c, 0, 0, 0, 1}}) {
    Volume<std::int16_t> turned = ct;
    turned.direction = D;
    const fs::path folder = dir / ("d" + std::to_string(D[0]));
    samples::write_dicom_series(turned, folder);
    const segment::SliceStack back = segment::read_dicom_series(folder);
    double hu = 0, direction = 0, origin = 0;
    for (std::size_t i = 0; i < ct.size(); ++i) hu = std::max(hu, std::abs(static_cast<double>(back.hu.data[i]) - ct.data[i]));
    for (int i = 0; i < 9; ++i) direction = std::max(direction, std::abs(back.hu.direction[i] - D[i]));
    for (int a = 0; a < 3; ++a) origin = std::max(origin, std::abs(back.hu.origin[a] - ct.origin[a]));
    std::printf("orientation %g\\%g\\%g\\%g\\%g\\%g: largest HU difference %g, direction %.1e, origin %.1e m\n", D[0], D[3], D[6], D[1], D[4], D[7],
                hu, direction, origin);
    EXPECT_EQ(back.hu.dims, ct.dims);
    EXPECT_EQ(hu, 0.0);
    EXPECT_LE(direction, 1e-6);  // DICOM stores cosines as decimal strings
    EXPECT_LE(origin, 1e-9);
  }
}
