// segment/stack_errors: each malformed slice stack stops with one InputError naming the file or
// field; a stack without bone says which thresholds were tried and how to set them.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "tactus/core/error.hpp"
#include "tactus/data_samples/phantom.hpp"
#include "tactus/segment/run.hpp"
#include "tactus/segment/stack.hpp"
#include "temp_dir.hpp"

using namespace tactus;

namespace {

class StackErrors : public ::testing::Test {
 protected:
  void SetUp() override {
    samples::PhantomParams p;
    p.voxel_mm = p.slice_mm = 4.0;  // a tiny stack
    samples::write_slice_stack(samples::make_hand_phantom(p).ct, dir / "stack");
  }
  void expect_error(std::initializer_list<std::string> fragments) {
    try {
      segment::read_slice_stack(dir / "stack");
      FAIL() << "expected an InputError";
    } catch (const InputError& e) {
      for (const auto& f : fragments) EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what();
    }
  }
  testkit::TempDir dir;
};

}  // namespace

TEST_F(StackErrors, ReadsValidStack) {
  const auto s = segment::read_slice_stack(dir / "stack");
  EXPECT_EQ(s.bit_depth, 16);
  EXPECT_NEAR(s.hu.spacing[0], 4e-3, 1e-15);  // mm in stack.json, metres inside
}
// 8-bit TIFF slices with their own rescale: HU = slope * stored + intercept, exactly.
TEST(SliceStack, ReadsEightBitTiff) {
  testkit::TempDir d;
  std::filesystem::create_directories(d / "s");
  for (int k = 0; k < 3; ++k) {
    cv::Mat img(5, 6, CV_8UC1);
    for (int y = 0; y < 5; ++y)
      for (int x = 0; x < 6; ++x) img.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(10 * k + 2 * y + x);
    char name[32];
    std::snprintf(name, sizeof name, "slice_%03d.tif", k + 7);  // numbering may start anywhere
    ASSERT_TRUE(cv::imwrite((d / "s" / name).string(), img));
  }
  std::ofstream(d / "s" / "stack.json") << R"({"spacing_mm": [0.5, 0.5, 1.25], "origin_mm": [1, 2, 3],
                                              "rescale_slope": 8, "rescale_intercept": -1000, "slices": 3})";
  const auto s = segment::read_slice_stack(d / "s");
  EXPECT_EQ(s.bit_depth, 8);
  ASSERT_EQ(s.hu.dims, (std::array<int, 3>{6, 5, 3}));
  EXPECT_FLOAT_EQ(s.hu.at(4, 3, 2), 8.0f * (20 + 6 + 4) - 1000.0f);
  EXPECT_DOUBLE_EQ(s.hu.spacing[2], 1.25e-3);
  EXPECT_DOUBLE_EQ(s.hu.origin[1], 2e-3);
}

TEST_F(StackErrors, MissingSliceInNumbering) {
  std::filesystem::remove(dir / "stack" / "slice_0005.png");
  expect_error({"slice 5", "missing", "slice_0006.png"});
}
TEST_F(StackErrors, SlicesOfDifferentSizes) {
  cv::imwrite((dir / "stack" / "slice_0003.png").string(), cv::Mat(7, 9, CV_16UC1, cv::Scalar(1000)));
  expect_error({"slice_0003.png", "like the first slice", "9 x 7"});
}
TEST_F(StackErrors, UnreadableSlice) {
  std::ofstream(dir / "stack" / "slice_0002.png") << "not a png";
  expect_error({"slice_0002.png", "unreadable"});
}
TEST_F(StackErrors, MissingStackJson) {
  std::filesystem::remove(dir / "stack" / "stack.json");
  expect_error({"stack.json", "missing"});
}
TEST_F(StackErrors, MalformedStackJson) {
  std::ofstream(dir / "stack" / "stack.json") << "{ \"spacing_mm\": [0.7, 0.7 ";
  expect_error({"stack.json", "malformed JSON"});
}
TEST_F(StackErrors, NonPositiveSpacing) {
  std::ofstream(dir / "stack" / "stack.json") << R"({"spacing_mm": [0.7, 0, 0.7]})";
  expect_error({"stack.json", "spacing_mm", "positive"});
}
// stack.json as written by the phantom, with one key replaced (or removed when value is empty).
namespace {
void edit_stack_json(const std::filesystem::path& file, const std::string& key, const std::string& value) {
  std::ifstream in(file);
  auto j = nlohmann::json::parse(in);
  if (value.empty())
    j.erase(key);
  else
    j[key] = nlohmann::json::parse(value);
  std::ofstream(file) << j.dump();
}
}  // namespace

// Silently wrong before: without the intercept the stored values were taken as HU.
TEST_F(StackErrors, MissingRescaleIntercept) {
  edit_stack_json(dir / "stack" / "stack.json", "rescale_intercept", "");
  expect_error({"stack.json", "rescale_intercept", "missing"});
}
// Silently wrong before: a missing first or last slice keeps the numbering contiguous.
TEST_F(StackErrors, MissingLastSliceCaughtByTheCount) {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir / "stack"))
    if (e.path().extension() == ".png") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::filesystem::remove(files.back());
  expect_error({"slices", "as stack.json says", "a first or last slice missing"});
}
TEST_F(StackErrors, SliceCountMustBeGiven) {
  edit_stack_json(dir / "stack" / "stack.json", "slices", "");
  expect_error({"stack.json", "slices", "missing"});
}
// These crashed or hung: spacing 1e308 (segfault), 1e-308 (endless remeshing), a slice number
// too large for stol ("internal error: stol").
TEST_F(StackErrors, AbsurdNumbersAreRefused) {
  edit_stack_json(dir / "stack" / "stack.json", "spacing_mm", "[0.7, 1e308, 0.7]");
  expect_error({"spacing_mm", "1e+308"});
  edit_stack_json(dir / "stack" / "stack.json", "spacing_mm", "[0.7, 1e-308, 0.7]");
  expect_error({"spacing_mm", "1e-308"});
  edit_stack_json(dir / "stack" / "stack.json", "spacing_mm", "[4, 4, 4]");
  std::ofstream(dir / "stack" / "slice_99999999999999999999.png") << "x";
  expect_error({"slice_99999999999999999999.png", "slice number"});
}
TEST_F(StackErrors, WrongJsonTypes) {
  edit_stack_json(dir / "stack" / "stack.json", "rescale_slope", "\"1\"");
  expect_error({"stack.json", "rescale_slope"});
  edit_stack_json(dir / "stack" / "stack.json", "rescale_slope", "1");
  edit_stack_json(dir / "stack" / "stack.json", "origin_mm", "{\"x\": 1}");
  expect_error({"stack.json", "origin_mm"});
}
// The PNG container is validated before any decoder sees it.
TEST_F(StackErrors, CorruptPngChunksAreRefused) {
  const auto slice = dir / "stack" / "slice_0002.png";
  std::fstream f(slice, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(40);  // inside the image data: its chunk's CRC no longer matches
  f.put('\x55');
  f.close();
  expect_error({"slice_0002.png", "CRC"});
  cv::imwrite(slice.string(), cv::Mat(5, 5, CV_8UC3, cv::Scalar(1, 2, 3)));
  expect_error({"slice_0002.png", "grey"});
}

TEST_F(StackErrors, NoBoneFound) {
  // A soft-tissue-only body: every slice a grey disc at 40 HU.
  testkit::TempDir d2;
  std::filesystem::create_directories(d2 / "s");
  for (int k = 0; k < 12; ++k) {
    cv::Mat img(40, 40, CV_16UC1, cv::Scalar(24));  // stored 24 -> -1000 HU
    for (int y = 0; y < 40; ++y)
      for (int x = 0; x < 40; ++x)
        if ((x - 20) * (x - 20) + (y - 20) * (y - 20) < 150) img.at<std::uint16_t>(y, x) = 1064;  // 40 HU
    char name[32];
    std::snprintf(name, sizeof name, "slice_%04d.png", k);
    cv::imwrite((d2 / "s" / name).string(), img);
  }
  std::ofstream(d2 / "s" / "stack.json") << R"({"spacing_mm": [1, 1, 1], "rescale_slope": 1, "rescale_intercept": -1024, "slices": 12})";
  segment::StageOptions o;
  o.write_surfaces = false;
  try {
    segment::run_segment_stage(d2 / "s", d2 / "out", o);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    for (const char* f : {"body threshold", "bone threshold", "--bone-threshold", "no bone"}) EXPECT_NE(msg.find(f), std::string::npos) << msg;
  }
}
