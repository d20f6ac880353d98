// core/volume: HDF5 and .vti round trips are exact; bad files give InputError naming the problem.
#include <gtest/gtest.h>

#include <fstream>
#include <random>

#include "tactus/core/error.hpp"
#include "tactus/core/volume.hpp"
#include "expect_error.hpp"
#include "temp_dir.hpp"

using namespace tactus;
using tactus::testkit::TempDir;
using tactus::testkit::expect_input_error;

namespace {

template <class T>
Volume<T> random_volume(std::uint32_t seed) {
  Volume<T> v({7, 5, 3}, {0.7e-3, 0.8e-3, 1.25e-3}, {-0.01, 0.02, 0.003});
  std::mt19937 rng(seed);
  for (auto& x : v.data) {
    if constexpr (std::is_floating_point_v<T>)
      x = std::uniform_real_distribution<T>(-1000, 3000)(rng);
    else
      x = static_cast<T>(std::uniform_int_distribution<int>(std::numeric_limits<T>::min(), std::numeric_limits<T>::max())(rng));
  }
  return v;
}

template <class T>
void expect_same(const Volume<T>& a, const Volume<T>& b) {
  EXPECT_EQ(a.dims, b.dims);
  EXPECT_EQ(a.spacing, b.spacing);  // exact: stored as IEEE doubles
  EXPECT_EQ(a.origin, b.origin);
  EXPECT_EQ(a.data, b.data);
}

template <class T>
class VolumeRoundTrip : public ::testing::Test {};
using VoxelTypes = ::testing::Types<std::uint8_t, std::uint16_t, std::int16_t, float>;
TYPED_TEST_SUITE(VolumeRoundTrip, VoxelTypes);

}  // namespace

// Oracle: the written values themselves; every voxel, spacing and origin must match exactly.
TYPED_TEST(VolumeRoundTrip, Hdf5PreservesEveryValue) {
  TempDir dir;
  const auto v = random_volume<TypeParam>(42);
  write_h5(dir / "v.h5", "/labels", v);
  expect_same(v, read_h5<TypeParam>(dir / "v.h5", "/labels"));
}

TYPED_TEST(VolumeRoundTrip, VtiPreservesEveryValue) {
  TempDir dir;
  const auto v = random_volume<TypeParam>(7);
  write_vti(dir / "v.vti", v, "ct");
  const auto back = read_vti<TypeParam>(dir / "v.vti", "ct");
  EXPECT_EQ(v.dims, back.dims);
  EXPECT_EQ(v.data, back.data);
  for (int a = 0; a < 3; ++a) {  // VTK XML writes doubles with full precision
    EXPECT_DOUBLE_EQ(v.spacing[a], back.spacing[a]);
    EXPECT_DOUBLE_EQ(v.origin[a], back.origin[a]);
  }
}

TEST(Volume, LabelTableRoundTrip) {
  TempDir dir;
  Volume<std::uint8_t> v({4, 4, 4}, {1e-3, 1e-3, 1e-3}, {0, 0, 0}, 1);
  LabelTable table{{0, "background"}, {1, "soft_tissue"}, {2, "scaphoid"}, {27, "distal_phalanx_5"}};
  write_h5(dir / "labels.h5", "/labels", v, &table);
  LabelTable back;
  read_h5<std::uint8_t>(dir / "labels.h5", "/labels", &back);
  EXPECT_EQ(table, back);
}

TEST(Volume, Uint8StoredReadsAsUint16) {
  TempDir dir;
  const auto v = random_volume<std::uint8_t>(3);
  write_h5(dir / "labels.h5", "/labels", v);
  const auto w = read_h5<std::uint16_t>(dir / "labels.h5", "/labels");
  ASSERT_EQ(v.size(), w.size());
  for (std::size_t i = 0; i < v.size(); ++i) EXPECT_EQ(v.data[i], w.data[i]);
}

TEST(VolumeErrors, MissingFile) {
  TempDir dir;
  expect_input_error([&] { read_h5<std::uint8_t>(dir / "nope.h5", "/labels"); }, {"nope.h5", "no such file"});
}

TEST(VolumeErrors, NotHdf5) {
  TempDir dir;
  std::ofstream(dir / "bad.h5") << "this is not an HDF5 file";
  expect_input_error([&] { read_h5<std::uint8_t>(dir / "bad.h5", "/labels"); }, {"bad.h5", "HDF5"});
}

TEST(VolumeErrors, TruncatedFile) {
  TempDir dir;
  Volume<std::uint16_t> v({64, 64, 16}, {1e-3, 1e-3, 1e-3}, {0, 0, 0});
  for (std::size_t i = 0; i < v.size(); ++i) v.data[i] = static_cast<std::uint16_t>(i * 2654435761u);
  write_h5(dir / "t.h5", "/labels", v);
  tactus::testkit::truncate_file(dir / "t.h5", std::filesystem::file_size(dir / "t.h5") / 2);
  expect_input_error([&] { read_h5<std::uint16_t>(dir / "t.h5", "/labels"); }, {"t.h5"});
}

TEST(VolumeErrors, WrongDatasetName) {
  TempDir dir;
  write_h5(dir / "v.h5", "/ct", random_volume<std::int16_t>(1));
  expect_input_error([&] { read_h5<std::uint8_t>(dir / "v.h5", "/labels"); }, {"v.h5", "/labels", "dataset"});
}

TEST(VolumeErrors, FloatVoxelsWhereLabelsExpected) {
  TempDir dir;
  write_h5(dir / "v.h5", "/labels", random_volume<float>(1));
  expect_input_error([&] { read_h5<std::uint8_t>(dir / "v.h5", "/labels"); }, {"integer voxels"});
}

TEST(VolumeErrors, NonPositiveSpacing) {
  TempDir dir;
  auto v = random_volume<std::uint8_t>(1);
  v.spacing[1] = 0;
  write_h5(dir / "v.h5", "/labels", v);
  expect_input_error([&] { read_h5<std::uint8_t>(dir / "v.h5", "/labels"); }, {"spacing", "positive"});
}

#include <hdf5.h>
// A dataset written by another tool without tactus' attributes: the error names the attribute.
TEST(VolumeErrors, MissingSpacingAttribute) {
  TempDir dir;
  const auto file = (dir / "raw.h5").string();
  hid_t f = H5Fcreate(file.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const hsize_t shape[3] = {2, 3, 4};
  hid_t space = H5Screate_simple(3, shape, nullptr);
  hid_t ds = H5Dcreate2(f, "/labels", H5T_NATIVE_UINT8, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  std::vector<std::uint8_t> data(24, 1);
  H5Dwrite(ds, H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data());
  H5Dclose(ds);
  H5Sclose(space);
  H5Fclose(f);
  expect_input_error([&] { read_h5<std::uint8_t>(file, "/labels"); }, {"raw.h5", "/labels@spacing"});
}
