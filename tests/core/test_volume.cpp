// core/volume: HDF5 and .vti round trips are exact; bad files give InputError naming the problem.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>

#include "expect_error.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/volume.hpp"
#include "tactus/core/volume_filters.hpp"
#include "temp_dir.hpp"

using namespace tactus;
using tactus::testkit::expect_input_error;
using tactus::testkit::TempDir;

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
  expect_input_error([&] { read_h5<std::uint8_t>(dir / "v.h5", "/labels"); }, {"spacing", "voxel size", "0 m along y"});
}

TEST(VolumeErrors, NonFiniteSpacingOrOrigin) {
  TempDir dir;
  auto v = random_volume<std::uint8_t>(1);
  v.spacing[0] = std::numeric_limits<double>::infinity();
  write_h5(dir / "v.h5", "/labels", v);
  expect_input_error([&] { read_h5<std::uint8_t>(dir / "v.h5", "/labels"); }, {"spacing", "inf m along x"});
  v = random_volume<std::uint8_t>(1);
  v.origin[2] = std::nan("");
  write_h5(dir / "w.h5", "/labels", v);
  expect_input_error([&] { read_h5<std::uint8_t>(dir / "w.h5", "/labels"); }, {"origin", "along z"});
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

namespace {

// A label dataset written with the HDF5 C API as another tool would: `type` voxels from `values`,
// tactus' spacing/origin attributes, and optionally a string attribute of the given kind.
enum class StringKind { none, fixed_nullterm, fixed_nullpad, fixed_spacepad, variable };

std::string write_foreign_labels(const std::filesystem::path& file, hid_t type, const std::vector<long long>& values, const hsize_t shape[3],
                                 StringKind kind = StringKind::none, const std::string& text = {}) {
  hid_t f = H5Fcreate(file.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  hid_t space = H5Screate_simple(3, shape, nullptr);
  hid_t plist = H5Pcreate(H5P_DATASET_CREATE);
  const hsize_t total = shape[0] * shape[1] * shape[2];
  if (total > 1000000) {  // a huge declared shape: chunked, nothing written
    const hsize_t chunk[3] = {1, 64, 64};
    H5Pset_chunk(plist, 3, chunk);
    H5Pset_deflate(plist, 4);
  }
  hid_t ds = H5Dcreate2(f, "/labels", type, space, H5P_DEFAULT, plist, H5P_DEFAULT);
  if (total <= 1000000) H5Dwrite(ds, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  const hsize_t three = 3;
  const double spacing[3] = {1e-3, 1e-3, 1e-3}, origin[3] = {0, 0, 0};
  for (auto [name, v] : {std::pair{"spacing", spacing}, std::pair{"origin", origin}}) {
    hid_t as = H5Screate_simple(1, &three, nullptr);
    hid_t a = H5Acreate2(ds, name, H5T_IEEE_F64LE, as, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a, H5T_NATIVE_DOUBLE, v);
    H5Aclose(a), H5Sclose(as);
  }
  if (kind != StringKind::none) {
    hid_t st = H5Tcopy(H5T_C_S1);
    hid_t scalar = H5Screate(H5S_SCALAR);
    if (kind == StringKind::variable) {
      H5Tset_size(st, H5T_VARIABLE);
      H5Tset_cset(st, H5T_CSET_UTF8);
      hid_t a = H5Acreate2(ds, "label_table", st, scalar, H5P_DEFAULT, H5P_DEFAULT);
      const char* p = text.c_str();
      H5Awrite(a, st, &p);
      H5Aclose(a);
    } else {
      std::string stored = text;
      if (kind == StringKind::fixed_nullterm) stored.push_back('\0');
      if (kind == StringKind::fixed_spacepad) stored += "   ";
      if (kind == StringKind::fixed_nullpad) stored += std::string(3, '\0');
      H5Tset_size(st, stored.size());
      H5Tset_strpad(st, kind == StringKind::fixed_spacepad  ? H5T_STR_SPACEPAD
                        : kind == StringKind::fixed_nullpad ? H5T_STR_NULLPAD
                                                            : H5T_STR_NULLTERM);
      hid_t a = H5Acreate2(ds, "label_table", st, scalar, H5P_DEFAULT, H5P_DEFAULT);
      H5Awrite(a, st, stored.data());
      H5Aclose(a);
    }
    H5Sclose(scalar), H5Tclose(st);
  }
  H5Dclose(ds), H5Pclose(plist), H5Sclose(space), H5Fclose(f);
  return file.string();
}

}  // namespace

// Every kind of string attribute HDF5 writers produce (h5py writes variable-length UTF-8 by
// default, other tools fixed-length with any padding) reads back whole: the last character of a
// NUL-padded string used to be cut, and variable-length ones were ignored.
TEST(VolumeStrings, EveryStringAttributeKindReadsWhole) {
  TempDir dir;
  const hsize_t shape[3] = {1, 1, 2};
  const std::string table = R"({"0": "air", "1": "soft_tissue", "2": "bone_02"})";
  for (auto kind : {StringKind::fixed_nullterm, StringKind::fixed_nullpad, StringKind::fixed_spacepad, StringKind::variable}) {
    const auto file = write_foreign_labels(dir / "l.h5", H5T_STD_U8LE, {1, 2}, shape, kind, table);
    LabelTable labels;
    const auto v = read_h5<std::uint8_t>(file, "/labels", &labels);
    ASSERT_EQ(labels.size(), 3u) << static_cast<int>(kind);
    EXPECT_EQ(labels.at(2), "bone_02") << static_cast<int>(kind);
    EXPECT_EQ(v.data, (std::vector<std::uint8_t>{1, 2}));
  }
}

// Stored values a uint8 label volume cannot hold are refused, naming value and voxel (HDF5's
// conversion used to clamp -1 to 0 and 300 to 255 silently).
TEST(VolumeErrors, LabelsOutsideTheVolumeTypeAreRefused) {
  TempDir dir;
  const hsize_t shape[3] = {1, 1, 3};
  expect_input_error(
      [&] {
        read_h5<std::uint8_t>(write_foreign_labels(dir / "a.h5", H5T_STD_I8LE, {1, -1, 2}, shape), "/labels");
      },
      {"a.h5", "-1 at voxel (x 1, y 0, z 0)", "[0, 255]"});
  expect_input_error(
      [&] {
        read_h5<std::uint8_t>(write_foreign_labels(dir / "b.h5", H5T_STD_I64LE, {1, 2, 300}, shape), "/labels");
      },
      {"b.h5", "300 at voxel (x 2"});
  // Values that fit are read whatever the stored type.
  const auto v = read_h5<std::uint8_t>(write_foreign_labels(dir / "c.h5", H5T_STD_I64LE, {0, 7, 255}, shape), "/labels");
  EXPECT_EQ(v.data, (std::vector<std::uint8_t>{0, 7, 255}));
}

// A 6 kB file that declares 50000^3 voxels is refused before anything is allocated.
TEST(VolumeErrors, DeclaredShapeMustBeBackedByTheFile) {
  TempDir dir;
  const hsize_t shape[3] = {50000, 50000, 50000};
  const auto file = write_foreign_labels(dir / "huge.h5", H5T_STD_U8LE, {}, shape);
  EXPECT_LT(std::filesystem::file_size(file), 100000u);
  expect_input_error([&] { read_h5<std::uint8_t>(file, "/labels"); }, {"huge.h5", "50000 x 50000 x 50000"});
}

// A corrupt HDF5 file (bytes overwritten inside the object headers) is an InputError naming the
// file, whatever libhdf5 does with it: it reads in an isolated child process.
TEST(VolumeErrors, CorruptHdf5IsAnInputErrorNeverACrash) {
  TempDir dir;
  write_h5(dir / "v.h5", "/labels", random_volume<std::uint8_t>(3));
  const auto size = std::filesystem::file_size(dir / "v.h5");
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    std::filesystem::copy_file(dir / "v.h5", dir / "c.h5", std::filesystem::copy_options::overwrite_existing);
    std::fstream f(dir / "c.h5", std::ios::in | std::ios::out | std::ios::binary);
    for (int k = 0; k < 16; ++k) {
      f.seekp(static_cast<std::streamoff>(std::uniform_int_distribution<std::uintmax_t>(0, size - 1)(rng)));
      f.put(static_cast<char>(rng()));
    }
    f.close();
    try {
      (void)read_h5<std::uint8_t>(dir / "c.h5", "/labels");
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("c.h5"), std::string::npos) << e.what();
    }
  }
}

// Oracle: a plain voxel-by-voxel flood fill of the background from the border (6-neighbours),
// written here. fill_holes (a scanline fill) must set exactly the voxels that fill does not reach,
// on random masks of several densities (tortuous background, cavities of every shape) and on a
// hollow box whose cavity must be filled.
TEST(VolumeFilters, FillHolesMatchesAVoxelByVoxelFloodFill) {
  std::mt19937 rng(5);
  std::size_t filled_total = 0;
  for (const double density : {0.2, 0.45, 0.6, 0.75}) {
    Volume<std::uint8_t> m({23, 17, 13}, {1, 1, 1}, {0, 0, 0}, 0);
    std::bernoulli_distribution on(density);
    for (auto& v : m.data) v = on(rng) ? 1 : 0;
    const auto& d = m.dims;
    std::vector<std::uint8_t> reached(m.size(), 0);
    std::vector<std::array<int, 3>> stack;
    for (int z = 0; z < d[2]; ++z)
      for (int y = 0; y < d[1]; ++y)
        for (int x = 0; x < d[0]; ++x)
          if ((x == 0 || y == 0 || z == 0 || x == d[0] - 1 || y == d[1] - 1 || z == d[2] - 1) && !m.at(x, y, z))
            reached[m.index(x, y, z)] = 1, stack.push_back({x, y, z});
    while (!stack.empty()) {
      const auto p = stack.back();
      stack.pop_back();
      for (int a = 0; a < 3; ++a)
        for (int s = -1; s <= 1; s += 2) {
          auto q = p;
          q[static_cast<std::size_t>(a)] += s;
          if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] >= d[0] || q[1] >= d[1] || q[2] >= d[2]) continue;
          const std::size_t i = m.index(q[0], q[1], q[2]);
          if (!m.data[i] && !reached[i]) reached[i] = 1, stack.push_back(q);
        }
    }
    Volume<std::uint8_t> f = m;
    fill_holes(f);
    std::size_t differ = 0, filled = 0;
    for (std::size_t i = 0; i < m.size(); ++i) {
      differ += f.data[i] != (reached[i] ? 0 : 1);
      filled += f.data[i] && !m.data[i];
    }
    std::printf("fill_holes, density %.2f: %zu holes filled, %zu voxels differ from the reference fill\n", density, filled, differ);
    EXPECT_EQ(differ, 0u);
    filled_total += filled;
  }
  EXPECT_GT(filled_total, 0u);
  Volume<std::uint8_t> box({9, 9, 9}, {1, 1, 1}, {0, 0, 0}, 0);
  for (int z = 1; z < 8; ++z)
    for (int y = 1; y < 8; ++y)
      for (int x = 1; x < 8; ++x) box.at(x, y, z) = (x == 1 || y == 1 || z == 1 || x == 7 || y == 7 || z == 7) ? 1 : 0;
  fill_holes(box);
  std::size_t inside = 0;
  for (auto v : box.data) inside += v;
  EXPECT_EQ(inside, 343u);  // the 7^3 box, cavity filled; the air around it stays
}
