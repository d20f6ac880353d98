#include "tactus/segment/volume_files.hpp"
#include "tactus/core/file_io.hpp"

#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"

namespace fs = std::filesystem;

namespace tactus::segment {

namespace {

enum class Scalar { u8, i8, u16, i16, u32, i32, f32, f64 };

std::size_t scalar_size(Scalar t) {
  switch (t) {
    case Scalar::u8:
    case Scalar::i8:
      return 1;
    case Scalar::u16:
    case Scalar::i16:
      return 2;
    case Scalar::u32:
    case Scalar::i32:
    case Scalar::f32:
      return 4;
    case Scalar::f64:
      return 8;
  }
  return 1;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return {};
  return s.substr(a, s.find_last_not_of(" \t\r") - a + 1);
}

std::string read_bytes(const fs::path& file, std::uint64_t cap, const std::string& what) {
  const auto size = require_regular_file(file, "a " + what);
  if (size > cap)
    throw InputError(file.string(), "", "a " + what + " of at most " + std::to_string(cap >> 20) + " MB", std::to_string(size) + " bytes");
  std::ifstream in(file, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// Inflates a gzip or zlib stream into exactly `expected` bytes (more or fewer is an error).
std::string inflate_exactly(const std::string& in, std::size_t expected, const std::string& file, const std::string& field) {
  // Deflate expands at most 1032:1: a header declaring more than that is refused before the
  // buffer is allocated (a 352-byte header declaring 7e8 voxels once reserved 2.6 GB).
  constexpr std::size_t kMaxDeflateRatio = 1032;
  if (expected / kMaxDeflateRatio > in.size())
    throw InputError(file, field,
                     std::to_string(expected) + " bytes of voxels as the header declares, which " + std::to_string(in.size()) +
                         " compressed bytes cannot hold (deflate expands at most 1032:1)",
                     "a file too short for its header (truncated, or a wrong size in the header)");
  std::string out(expected, '\0');
  z_stream z{};
  if (inflateInit2(&z, 15 + 32) != Z_OK) throw Error("zlib: cannot start inflating");
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data()));
  z.avail_in = static_cast<uInt>(std::min<std::size_t>(in.size(), 0xFFFFFFFFu));
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(expected);
  const int rc = inflate(&z, Z_FINISH);
  const std::size_t produced = expected - z.avail_out;
  inflateEnd(&z);
  if (rc == Z_BUF_ERROR && produced == expected)
    throw InputError(file, field, std::to_string(expected) + " bytes of voxels as the header declares", "more compressed data");
  if (rc != Z_STREAM_END || produced != expected)
    throw InputError(file, field, std::to_string(expected) + " bytes of compressed voxels as the header declares",
                     std::to_string(produced) + " bytes (truncated or corrupt compressed data)");
  return out;
}

// w <= 8 bytes at p into b, reversed when `swap` (the other byte order than this machine's).
void load_bytes(const unsigned char* p, std::size_t w, bool swap, unsigned char* b) {
  for (std::size_t k = 0; k < w && k < 8; ++k) b[k] = p[swap ? w - 1 - k : k];
}

template <class T>
double value_as(const unsigned char* b) {
  T x;
  std::memcpy(&x, b, sizeof x);
  return static_cast<double>(x);
}

// Stored values (of type t, in the given byte order) as HU = slope * v + intercept.
void convert(const char* bytes, std::size_t n, Scalar t, bool big, double slope, double intercept, float* out, const std::string& file) {
  const std::size_t w = scalar_size(t);
  const bool swap = big != (std::endian::native == std::endian::big);
  unsigned char b[8] = {};
  for (std::size_t i = 0; i < n; ++i) {
    load_bytes(reinterpret_cast<const unsigned char*>(bytes) + i * w, w, swap, b);
    double v = 0;
    switch (t) {
      case Scalar::u8:
        v = value_as<std::uint8_t>(b);
        break;
      case Scalar::i8:
        v = value_as<std::int8_t>(b);
        break;
      case Scalar::u16:
        v = value_as<std::uint16_t>(b);
        break;
      case Scalar::i16:
        v = value_as<std::int16_t>(b);
        break;
      case Scalar::u32:
        v = value_as<std::uint32_t>(b);
        break;
      case Scalar::i32:
        v = value_as<std::int32_t>(b);
        break;
      case Scalar::f32:
        v = value_as<float>(b);
        break;
      case Scalar::f64:
        v = value_as<double>(b);
        break;
    }
    const double hu = slope * v + intercept;
    if (!std::isfinite(hu) || std::abs(hu) > 1e7)
      throw InputError(file, "voxel " + std::to_string(i), "a finite value within 1e7 HU", std::to_string(hu));
    out[i] = static_cast<float>(hu);
  }
}

// The volume from an affine in mm: column a of M is the step along voxel axis a, o the first
// voxel's centre; `ras`: M and o are in the RAS frame (turned into LPS here).
SliceStack make_stack(const std::array<int, 3>& dims, double M[3][3], double o[3], bool ras, const std::string& file, const std::string& field) {
  if (ras)
    for (int c = 0; c < 3; ++c) M[0][c] = -M[0][c], M[1][c] = -M[1][c];
  if (ras) o[0] = -o[0], o[1] = -o[1];
  SliceStack s;
  std::array<double, 3> spacing{};
  Direction d{};
  for (int a = 0; a < 3; ++a) {
    spacing[static_cast<std::size_t>(a)] = std::sqrt(M[0][a] * M[0][a] + M[1][a] * M[1][a] + M[2][a] * M[2][a]);
    if (!(spacing[static_cast<std::size_t>(a)] > 0)) throw InputError(file, field, "a non-zero voxel step along every axis", "a zero step");
    for (int r = 0; r < 3; ++r) d[static_cast<std::size_t>(3 * r + a)] = M[r][a] / spacing[static_cast<std::size_t>(a)];
  }
  validate_direction(d, file, field + " (a sheared or skewed affine is not supported: resample it first)");
  const std::array<double, 3> spacing_m{spacing[0] * 1e-3, spacing[1] * 1e-3, spacing[2] * 1e-3}, origin_m{o[0] * 1e-3, o[1] * 1e-3, o[2] * 1e-3};
  validate_volume_geometry(dims, spacing_m, origin_m, sizeof(float), file, field);
  s.hu = Volume<float>(dims, spacing_m, origin_m);
  s.hu.direction = d;
  return s;
}

std::size_t voxel_count(const std::array<int, 3>& d) {
  return static_cast<std::size_t>(d[0]) * static_cast<std::size_t>(d[1]) * static_cast<std::size_t>(d[2]);
}

constexpr std::uint64_t kMaxBytes = std::uint64_t{16} << 30;

// ---- NIfTI-1 ---------------------------------------------------------------------------------

// The first `bytes` bytes of a gzip stream (fewer when it is shorter).
std::string inflate_prefix(std::string& compressed, std::size_t bytes) {
  std::string part(bytes, '\0');
  z_stream z{};
  inflateInit2(&z, 15 + 32);
  z.next_in = reinterpret_cast<Bytef*>(compressed.data());
  z.avail_in = static_cast<uInt>(std::min<std::size_t>(compressed.size(), 0xFFFFFFFFu));
  z.next_out = reinterpret_cast<Bytef*>(part.data());
  z.avail_out = static_cast<uInt>(bytes);
  inflate(&z, Z_SYNC_FLUSH);
  const std::size_t got = bytes - z.avail_out;
  inflateEnd(&z);
  return part.substr(0, got);
}

// The voxel-to-world affine of a NIfTI-1 header (M: columns per voxel axis, o: the first voxel's
// centre, both in mm), from its sform, else its qform, else the voxel sizes alone; i16 and f32
// read the header's fields at a byte offset. Returns whether the frame is RAS (false: no
// transform given, axis-aligned at the origin).
template <class I16, class F32>
bool nifti_affine(const I16& i16, const F32& f32, const double pixdim[4], int units, const std::string& file, double M[3][3], double o[3]) {
  const double to_mm = units == 1 ? 1e3 : units == 3 ? 1e-3 : 1.0;  // metres, micrometres; mm or unknown: mm
  bool ras = true;
  if (i16(254) > 0) {  // sform: the affine itself
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) M[r][c] = f32(280 + 16 * static_cast<std::size_t>(r) + 4 * static_cast<std::size_t>(c));
      o[r] = f32(280 + 16 * static_cast<std::size_t>(r) + 12);
    }
  } else if (i16(252) > 0) {  // qform: a quaternion rotation, the voxel sizes, qfac for the third axis
    const double b = f32(256), c = f32(260), d = f32(264), bcd = b * b + c * c + d * d;
    // a = sqrt(1 - b^2 - c^2 - d^2): (b, c, d) past the unit sphere is no rotation (seen: a spacing of
    // 36 um for 3 mm voxels). A few ulps over 1 from float rounding is a = 0, as NIfTI's reference code does.
    if (!std::isfinite(bcd) || bcd > 1 + 1e-5)
      throw InputError(file, "quatern_b/c/d", "the vector part of a unit quaternion (b^2 + c^2 + d^2 <= 1)",
                       "b^2 + c^2 + d^2 = " + std::to_string(bcd));
    const double a = std::sqrt(std::max(0.0, 1 - bcd));
    const double R[3][3] = {{a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c)},
                            {2 * (b * c + a * d), a * a + c * c - b * b - d * d, 2 * (c * d - a * b)},
                            {2 * (b * d - a * c), 2 * (c * d + a * b), a * a + d * d - c * c - b * b}};
    const double step[3] = {pixdim[1], pixdim[2], pixdim[3] * (pixdim[0] < 0 ? -1 : 1)};
    for (int r = 0; r < 3; ++r)
      for (int col = 0; col < 3; ++col) M[r][col] = R[r][col] * step[col];
    o[0] = f32(268), o[1] = f32(272), o[2] = f32(276);
  } else {  // no transform (NIfTI's method 1): the voxel sizes only, axis-aligned
    for (int a = 0; a < 3; ++a) M[a][a] = pixdim[a + 1];
    ras = false;
    log::info() << file << ": no qform or sform; axis-aligned voxels at the origin";
  }
  for (int r = 0; r < 3; ++r) {
    o[r] *= to_mm;
    for (int c = 0; c < 3; ++c) M[r][c] *= to_mm;
  }
  return ras;
}

SliceStack read_nifti(const fs::path& path) {
  const std::string file = path.string();
  std::string raw = read_bytes(path, kMaxBytes, "NIfTI file");
  const bool gz = raw.size() >= 2 && static_cast<unsigned char>(raw[0]) == 0x1F && static_cast<unsigned char>(raw[1]) == 0x8B;
  // The header first (to know how many voxel bytes to expect), then all of it.
  const std::string head = gz ? inflate_prefix(raw, 352) : raw;
  if (head.size() < 348) throw InputError(file, "header", "a 348-byte NIfTI-1 header", std::to_string(head.size()) + " bytes (truncated)");
  const auto* h = reinterpret_cast<const unsigned char*>(head.data());
  std::int32_t sizeof_hdr;
  std::memcpy(&sizeof_hdr, h, 4);
  bool big = false;
  if (sizeof_hdr != 348) {
    std::uint32_t u;
    std::memcpy(&u, h, 4);
    u = __builtin_bswap32(u);
    if (u != 348) throw InputError(file, "sizeof_hdr", "348 (a NIfTI-1 header; NIfTI-2 is not supported)", std::to_string(sizeof_hdr));
    big = true;
  }
  const bool swap = big != (std::endian::native == std::endian::big);
  unsigned char word[8] = {};
  auto i16 = [&](std::size_t off) {
    load_bytes(h + off, 2, swap, word);
    return static_cast<int>(value_as<std::int16_t>(word));
  };
  auto f32 = [&](std::size_t off) {
    load_bytes(h + off, 4, swap, word);
    return value_as<float>(word);
  };
  if (std::memcmp(h + 344, "n+1\0", 4) != 0)
    throw InputError(file, "magic", "\"n+1\" (a single-file .nii; a .hdr/.img pair is not supported)",
                     std::string(reinterpret_cast<const char*>(h + 344), 3));
  const int ndim = i16(40);
  std::array<int, 3> dims{i16(42), i16(44), i16(46)};
  if (ndim < 3 || ndim > 7) throw InputError(file, "dim[0]", "3 dimensions (or more of size 1)", std::to_string(ndim));
  for (int k = 4; k <= ndim; ++k)
    if (i16(40 + 2 * static_cast<std::size_t>(k)) != 1)
      throw InputError(file, "dim[" + std::to_string(k) + "]", "1 (one volume, one channel)",
                       std::to_string(i16(40 + 2 * static_cast<std::size_t>(k))));
  for (int a = 0; a < 3; ++a)
    if (dims[static_cast<std::size_t>(a)] < 1)
      throw InputError(file, "dim[" + std::to_string(a + 1) + "]", "at least 1 voxel", std::to_string(dims[static_cast<std::size_t>(a)]));
  static const std::map<int, Scalar> types{{2, Scalar::u8},   {4, Scalar::i16},  {8, Scalar::i32},   {16, Scalar::f32},
                                           {64, Scalar::f64}, {256, Scalar::i8}, {512, Scalar::u16}, {768, Scalar::u32}};
  const auto type = types.find(i16(70));
  if (type == types.end()) throw InputError(file, "datatype", "a scalar voxel type (uint8/16/32, int8/16/32, float32/64)", std::to_string(i16(70)));
  double pixdim[4];
  for (int k = 0; k < 4; ++k) pixdim[k] = f32(76 + 4 * static_cast<std::size_t>(k));
  const double vox_offset = f32(108);
  if (!(vox_offset >= 348 && vox_offset < 1e9) || vox_offset != std::floor(vox_offset))
    throw InputError(file, "vox_offset", "a whole byte offset of at least 348", std::to_string(vox_offset));
  double slope = f32(112), intercept = f32(116);
  if (!std::isfinite(slope) || slope == 0) slope = 1, intercept = 0;  // the standard: 0 means no scaling
  if (!std::isfinite(intercept)) intercept = 0;
  double M[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}}, o[3] = {0, 0, 0};
  const bool ras = nifti_affine(i16, f32, pixdim, h[123] & 7, file, M, o);
  // The declared size against the file's before anything of that size is allocated.
  const std::size_t n = voxel_count(dims), bytes = n * scalar_size(type->second), offset = static_cast<std::size_t>(vox_offset);
  if (gz) raw = inflate_exactly(raw, offset + bytes, file, "voxels");
  if (raw.size() < offset + bytes)
    throw InputError(file, "voxels", std::to_string(bytes) + " bytes of voxels after byte " + std::to_string(offset),
                     std::to_string(raw.size() - std::min(raw.size(), offset)) + " (truncated)");
  SliceStack s = make_stack(dims, M, o, ras, file, "qform/sform");
  convert(raw.data() + offset, n, type->second, big, slope, intercept, s.hu.data.data(), file);
  s.source = "NIfTI file " + file;
  return s;
}

// ---- text headers (NRRD, MetaImage) ------------------------------------------------------------

std::vector<double> numbers(const std::string& text, std::size_t count, const std::string& file, const std::string& field) {
  std::string t = text;
  std::replace_if(
      t.begin(), t.end(), [](char c) { return c == '(' || c == ')' || c == ','; }, ' ');
  std::istringstream in(t);
  std::vector<double> v;
  std::string word;
  while (in >> word) {
    char* end = nullptr;
    const double x = std::strtod(word.c_str(), &end);
    if (end != word.c_str() + word.size() || !std::isfinite(x)) throw InputError(file, field, std::to_string(count) + " numbers", text.substr(0, 80));
    v.push_back(x);
  }
  if (v.size() != count) throw InputError(file, field, std::to_string(count) + " numbers", text.substr(0, 80));
  return v;
}

std::array<int, 3> sizes(const std::string& text, const std::string& file, const std::string& field) {
  const std::vector<double> v = numbers(text, 3, file, field);
  std::array<int, 3> d{};
  for (int a = 0; a < 3; ++a) {
    if (!(v[static_cast<std::size_t>(a)] >= 1 && v[static_cast<std::size_t>(a)] <= kMaxVolumeDim) ||
        v[static_cast<std::size_t>(a)] != std::floor(v[static_cast<std::size_t>(a)]))
      throw InputError(file, field, "3 whole sizes of 1 to " + std::to_string(kMaxVolumeDim), text.substr(0, 80));
    d[static_cast<std::size_t>(a)] = static_cast<int>(v[static_cast<std::size_t>(a)]);
  }
  return d;
}

// The voxels of a text-headed format: `data` (attached after the header, or a detached file's
// bytes), raw or compressed, counted against the header.
void fill_voxels(SliceStack& s, const std::string& data, bool compressed, Scalar t, bool big, const std::string& file) {
  const std::size_t n = s.hu.size(), bytes = n * scalar_size(t);
  const std::string inflated = compressed ? inflate_exactly(data, bytes, file, "voxels") : std::string();
  const std::string& v = compressed ? inflated : data;
  if (v.size() != bytes)
    throw InputError(file, "voxels", std::to_string(bytes) + " bytes of voxels as the header declares",
                     std::to_string(v.size()) + (v.size() < bytes ? " (truncated)" : " (extra bytes)"));
  convert(v.data(), n, t, big, 1.0, 0.0, s.hu.data.data(), file);
}

// Header lines up to the first empty line (NRRD) or the ElementDataFile line (MetaImage).
struct TextHeader {
  std::vector<std::pair<std::string, std::string>> fields;  // in order
  std::size_t data_start = 0;                               // byte after the header
};

// NRRD's scalar type names.
const std::map<std::string, Scalar> kNrrdTypes{{"signed char", Scalar::i8},
                                               {"int8", Scalar::i8},
                                               {"int8_t", Scalar::i8},
                                               {"uchar", Scalar::u8},
                                               {"unsigned char", Scalar::u8},
                                               {"uint8", Scalar::u8},
                                               {"uint8_t", Scalar::u8},
                                               {"short", Scalar::i16},
                                               {"short int", Scalar::i16},
                                               {"signed short", Scalar::i16},
                                               {"signed short int", Scalar::i16},
                                               {"int16", Scalar::i16},
                                               {"int16_t", Scalar::i16},
                                               {"ushort", Scalar::u16},
                                               {"unsigned short", Scalar::u16},
                                               {"unsigned short int", Scalar::u16},
                                               {"uint16", Scalar::u16},
                                               {"uint16_t", Scalar::u16},
                                               {"int", Scalar::i32},
                                               {"signed int", Scalar::i32},
                                               {"int32", Scalar::i32},
                                               {"int32_t", Scalar::i32},
                                               {"uint", Scalar::u32},
                                               {"unsigned int", Scalar::u32},
                                               {"uint32", Scalar::u32},
                                               {"uint32_t", Scalar::u32},
                                               {"float", Scalar::f32},
                                               {"double", Scalar::f64}};

// The header fields of a NRRD file (lower-case names), up to the empty line that ends them;
// data_start: the byte after it (npos when there is none, as with a detached data file).
std::map<std::string, std::string> nrrd_fields(const std::string& raw, const std::string& file, std::size_t& data_start) {
  std::map<std::string, std::string> f;
  std::size_t pos = raw.find('\n');
  while (pos != std::string::npos && pos + 1 <= raw.size() && pos < (1u << 16)) {
    const std::size_t next = raw.find('\n', pos + 1);
    std::string line = raw.substr(pos + 1, next == std::string::npos ? std::string::npos : next - pos - 1);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) {
      data_start = next == std::string::npos ? raw.size() : next + 1;
      break;
    }
    pos = next;
    if (line[0] == '#' || line.find(":=") != std::string::npos) continue;  // comments, key/value pairs
    const auto colon = line.find(": ");
    if (colon == std::string::npos) throw InputError(file, "header", "\"field: value\" lines", line.substr(0, 60));
    f[lower(trim(line.substr(0, colon)))] = trim(line.substr(colon + 2));
  }
  return f;
}

// The voxel-to-world affine of a NRRD header (M: columns per voxel axis, o: the first voxel's
// centre, mm), from its space directions, or its spacings alone; whether its space is RAS.
template <class Need>
bool nrrd_affine(const std::map<std::string, std::string>& f, const Need& need, const std::string& file, double M[3][3], double o[3]) {
  bool ras = false;
  if (f.count("space directions")) {
    const std::vector<double> v = numbers(f.at("space directions"), 9, file, "space directions");
    for (int a = 0; a < 3; ++a)
      for (int r = 0; r < 3; ++r) M[r][a] = v[static_cast<std::size_t>(3 * a + r)];  // one vector per axis
    const std::string space = lower(need("space"));
    if (space == "right-anterior-superior" || space == "ras")
      ras = true;
    else if (space != "left-posterior-superior" && space != "lps")
      throw InputError(file, "space", "left-posterior-superior or right-anterior-superior (3-D patient spaces)", space);
    if (f.count("space origin")) {
      const std::vector<double> v2 = numbers(f.at("space origin"), 3, file, "space origin");
      for (int r = 0; r < 3; ++r) o[r] = v2[static_cast<std::size_t>(r)];
    }
    if (f.count("space units")) {
      std::string u = lower(f.at("space units"));
      u.erase(std::remove_if(u.begin(), u.end(), [](char c) { return c == '"' || c == ' '; }), u.end());
      if (u != "mmmmmm") throw InputError(file, "space units", "\"mm\" \"mm\" \"mm\"", f.at("space units"));
    }
  } else {
    const std::vector<double> v = numbers(need("spacings"), 3, file, "spacings");
    for (int a = 0; a < 3; ++a) M[a][a] = v[static_cast<std::size_t>(a)];
  }
  return ras;
}

SliceStack read_nrrd(const fs::path& path) {
  const std::string file = path.string();
  const std::string raw = read_bytes(path, kMaxBytes, "NRRD file");
  if (raw.compare(0, 7, "NRRD000") != 0 || raw.size() < 9) throw InputError(file, "", "a NRRD file (NRRD0001..5 on the first line)", "no NRRD magic");
  std::size_t data_start = std::string::npos;
  const std::map<std::string, std::string> f = nrrd_fields(raw, file, data_start);
  const bool detached = f.count("data file") || f.count("datafile");
  if (data_start == std::string::npos && !detached)
    throw InputError(file, "header", "a header ended by an empty line, then the voxels", "no end of header (truncated)");
  auto need = [&](const char* key) -> const std::string& {
    if (!f.count(key)) throw InputError(file, key, "a \"" + std::string(key) + "\" field", "missing");
    return f.at(key);
  };
  const auto type = kNrrdTypes.find(lower(need("type")));
  if (type == kNrrdTypes.end()) throw InputError(file, "type", "a scalar type (int8..uint32, float, double)", need("type"));
  if (trim(need("dimension")) != "3") throw InputError(file, "dimension", "3", need("dimension"));
  const std::array<int, 3> dims = sizes(need("sizes"), file, "sizes");
  const std::string encoding = lower(need("encoding"));
  if (encoding != "raw" && encoding != "gzip" && encoding != "gz") throw InputError(file, "encoding", "raw or gzip", encoding);
  bool big = false;
  if (scalar_size(type->second) > 1) {
    const std::string e = lower(need("endian"));
    if (e != "little" && e != "big") throw InputError(file, "endian", "little or big", e);
    big = e == "big";
  }
  for (const char* key : {"byte skip", "byteskip", "line skip", "lineskip"})
    if (f.count(key) && trim(f.at(key)) != "0") throw InputError(file, key, "0 (skips are not supported)", f.at(key));
  double M[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}}, o[3] = {0, 0, 0};
  const bool ras = nrrd_affine(f, need, file, M, o);
  SliceStack s = make_stack(dims, M, o, ras, file, "space directions");
  std::string data;
  if (detached) {
    const std::string name = f.count("data file") ? f.at("data file") : f.at("datafile");
    if (name.rfind("LIST", 0) == 0 || name.find('%') != std::string::npos) throw InputError(file, "data file", "one data file", name);
    const fs::path data_path = fs::path(name).is_absolute() ? fs::path(name) : path.parent_path() / name;
    data = read_bytes(data_path, kMaxBytes, "NRRD data file");
  } else {
    data = raw.substr(data_start);
  }
  fill_voxels(s, data, encoding != "raw", type->second, big, file);
  s.source = "NRRD file " + file;
  return s;
}

SliceStack read_metaimage(const fs::path& path) {
  const std::string file = path.string();
  const std::string raw = read_bytes(path, kMaxBytes, "MetaImage file");
  std::map<std::string, std::string> f;
  std::size_t pos = 0, data_start = std::string::npos;
  while (pos < raw.size() && pos < (1u << 16)) {
    const std::size_t next = raw.find('\n', pos);
    std::string line = raw.substr(pos, next == std::string::npos ? std::string::npos : next - pos);
    pos = next == std::string::npos ? raw.size() : next + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (trim(line).empty()) continue;
    const auto eq = line.find('=');
    if (eq == std::string::npos) throw InputError(file, "header", "\"Key = Value\" lines", line.substr(0, 60));
    const std::string key = lower(trim(line.substr(0, eq)));
    f[key] = trim(line.substr(eq + 1));
    if (key == "elementdatafile") {
      data_start = pos;
      break;
    }
  }
  if (data_start == std::string::npos)
    throw InputError(file, "ElementDataFile", "a header ending with ElementDataFile", "none (not a MetaImage, or truncated)");
  auto need = [&](const char* key, const char* shown) -> const std::string& {
    if (!f.count(key)) throw InputError(file, shown, "a " + std::string(shown) + " line", "missing");
    return f.at(key);
  };
  if (f.count("objecttype") && lower(f.at("objecttype")) != "image") throw InputError(file, "ObjectType", "Image", f.at("objecttype"));
  if (trim(need("ndims", "NDims")) != "3") throw InputError(file, "NDims", "3", f.at("ndims"));
  const std::array<int, 3> dims = sizes(need("dimsize", "DimSize"), file, "DimSize");
  static const std::map<std::string, Scalar> types{{"met_uchar", Scalar::u8},  {"met_char", Scalar::i8},   {"met_ushort", Scalar::u16},
                                                   {"met_short", Scalar::i16}, {"met_uint", Scalar::u32},  {"met_int", Scalar::i32},
                                                   {"met_float", Scalar::f32}, {"met_double", Scalar::f64}};
  const auto type = types.find(lower(need("elementtype", "ElementType")));
  if (type == types.end()) throw InputError(file, "ElementType", "MET_UCHAR .. MET_DOUBLE (one scalar per voxel)", f.at("elementtype"));
  if (f.count("elementnumberofchannels") && trim(f.at("elementnumberofchannels")) != "1")
    throw InputError(file, "ElementNumberOfChannels", "1", f.at("elementnumberofchannels"));
  if (f.count("headersize") && trim(f.at("headersize")) != "0") throw InputError(file, "HeaderSize", "0", f.at("headersize"));
  auto truthy = [&](const char* key) { return f.count(key) && lower(f.at(key)) == "true"; };
  const bool big = truthy("elementbyteordermsb") || truthy("binarydatabyteordermsb");
  const bool compressed = truthy("compresseddata");
  const std::string spacing_key = f.count("elementspacing") ? "elementspacing" : "elementsize";
  const std::vector<double> spacing = numbers(need(spacing_key.c_str(), "ElementSpacing"), 3, file, "ElementSpacing");
  std::vector<double> offset{0, 0, 0}, matrix{1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (const char* key : {"offset", "origin", "position"})
    if (f.count(key)) offset = numbers(f.at(key), 3, file, "Offset");
  for (const char* key : {"transformmatrix", "rotation", "orientation"})
    if (f.count(key)) matrix = numbers(f.at(key), 9, file, "TransformMatrix");
  double M[3][3], o[3];
  for (int a = 0; a < 3; ++a) {
    o[a] = offset[static_cast<std::size_t>(a)];
    for (int r = 0; r < 3; ++r)
      M[r][a] = matrix[static_cast<std::size_t>(3 * a + r)] * spacing[static_cast<std::size_t>(a)];  // triple a: axis a's direction (ITK)
  }
  SliceStack s = make_stack(dims, M, o, false, file, "TransformMatrix");
  const std::string data_file = f.at("elementdatafile");
  std::string data;
  if (lower(data_file) == "local") {
    data = raw.substr(data_start);
  } else {
    if (data_file.rfind("LIST", 0) == 0 || data_file.find('%') != std::string::npos)
      throw InputError(file, "ElementDataFile", "LOCAL or one data file", data_file);
    const fs::path data_path = fs::path(data_file).is_absolute() ? fs::path(data_file) : path.parent_path() / data_file;
    data = read_bytes(data_path, kMaxBytes, "MetaImage data file");
  }
  fill_voxels(s, data, compressed, type->second, big, file);
  s.source = "MetaImage file " + file;
  return s;
}

// ---- INRIMAGE-4 ------------------------------------------------------------------------------

// Inria's format, which CGAL's image meshers read: "#INRIMAGE-4#{", "KEY=value" lines, newline
// padding to a multiple of 256 bytes, "##}\n", then the raw voxels x fastest (.inr.gz: the whole
// file gzipped). It has no orientation: the axes are the world's, the origin XO/YO/ZO (mm; 0 when
// absent). Lines starting with '#' (#GEOMETRY=CARTESIAN) are comments.
SliceStack read_inrimage(const fs::path& path) {
  const std::string file = path.string();
  std::string raw = read_bytes(path, kMaxBytes, "INRIMAGE file");
  const bool gz = raw.size() >= 2 && static_cast<unsigned char>(raw[0]) == 0x1F && static_cast<unsigned char>(raw[1]) == 0x8B;
  constexpr std::size_t kMaxHeader = 64 * 256;
  const std::string head = gz ? inflate_prefix(raw, kMaxHeader) : raw.substr(0, std::min(raw.size(), kMaxHeader));
  if (head.rfind("#INRIMAGE-4#{\n", 0) != 0)
    throw InputError(file, "magic", "\"#INRIMAGE-4#{\" (an INRIMAGE-4 header)", "other bytes (not an INRIMAGE file)");
  const auto close = head.find("##}\n");
  if (close == std::string::npos) throw InputError(file, "header", "a header closed by \"##}\" within 16 kB", "none (truncated, or not INRIMAGE)");
  const std::size_t header_bytes = close + 4;
  if (header_bytes % 256 != 0) throw InputError(file, "header", "a header of a multiple of 256 bytes", std::to_string(header_bytes) + " bytes");
  std::map<std::string, std::string> f;
  std::istringstream lines(head.substr(14, close - 14));
  for (std::string line; std::getline(lines, line);) {
    if (trim(line).empty() || line[0] == '#') continue;
    const auto eq = line.find('=');
    if (eq == std::string::npos) throw InputError(file, "header", "KEY=value lines", line.substr(0, 60));
    f[trim(line.substr(0, eq))] = trim(line.substr(eq + 1));
  }
  auto need = [&](const char* key) -> const std::string& {
    if (!f.count(key)) throw InputError(file, key, "a " + std::string(key) + "= line", "missing");
    return f.at(key);
  };
  const std::array<int, 3> dims = sizes(need("XDIM") + " " + need("YDIM") + " " + need("ZDIM"), file, "XDIM/YDIM/ZDIM");
  if (f.count("VDIM") && f.at("VDIM") != "1") throw InputError(file, "VDIM", "1 (one scalar per voxel)", f.at("VDIM"));
  const std::string type = lower(need("TYPE")), bits = lower(need("PIXSIZE"));
  static const std::map<std::string, Scalar> kTypes{{"unsigned fixed 8 bits", Scalar::u8},   {"signed fixed 8 bits", Scalar::i8},
                                                    {"unsigned fixed 16 bits", Scalar::u16}, {"signed fixed 16 bits", Scalar::i16},
                                                    {"unsigned fixed 32 bits", Scalar::u32}, {"signed fixed 32 bits", Scalar::i32},
                                                    {"float 32 bits", Scalar::f32},          {"float 64 bits", Scalar::f64}};
  const auto t = kTypes.find(type + " " + bits);
  if (t == kTypes.end())
    throw InputError(file, "TYPE/PIXSIZE", "unsigned or signed fixed of 8, 16 or 32 bits, or float of 32 or 64 bits", type + ", " + bits);
  // CPU: the byte order of the voxels (decm, alpha, pc: little-endian; sun, sgi: big-endian).
  const std::string cpu = f.count("CPU") ? lower(f.at("CPU")) : "decm";
  if (cpu != "decm" && cpu != "alpha" && cpu != "pc" && cpu != "sun" && cpu != "sgi")
    throw InputError(file, "CPU", "decm, alpha, pc (little-endian), sun or sgi (big-endian)", cpu);
  const bool big = cpu == "sun" || cpu == "sgi";
  double M[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}}, o[3] = {0, 0, 0};
  const char* step_keys[3] = {"VX", "VY", "VZ"};
  const char* origin_keys[3] = {"XO", "YO", "ZO"};
  for (int a = 0; a < 3; ++a) {
    M[a][a] = f.count(step_keys[a]) ? numbers(f.at(step_keys[a]), 1, file, step_keys[a])[0] : 1.0;
    if (f.count(origin_keys[a])) o[a] = numbers(f.at(origin_keys[a]), 1, file, origin_keys[a])[0];
  }
  SliceStack s = make_stack(dims, M, o, false, file, "VX/VY/VZ");
  const std::size_t bytes = voxel_count(dims) * scalar_size(t->second);
  if (gz) raw = inflate_exactly(raw, header_bytes + bytes, file, "voxels");
  fill_voxels(s, raw.substr(std::min(raw.size(), header_bytes)), false, t->second, big, file);
  s.source = "INRIMAGE file " + file;
  return s;
}

std::string kind_of(const fs::path& file) {
  const std::string name = lower(file.filename().string());
  auto ends = [&](const std::string& e) { return name.size() > e.size() && name.compare(name.size() - e.size(), e.size(), e) == 0; };
  if (ends(".nii") || ends(".nii.gz")) return "nifti";
  if (ends(".nrrd") || ends(".nhdr")) return "nrrd";
  if (ends(".mha") || ends(".mhd")) return "metaimage";
  if (ends(".inr") || ends(".inr.gz")) return "inrimage";
  return {};
}

}  // namespace

bool is_volume_file(const fs::path& file) { return !kind_of(file).empty(); }

SliceStack read_volume_file(const fs::path& file) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) throw InputError(file.string(), "", "an existing CT volume file", "no such file");
  const std::string kind = kind_of(file);
  if (kind.empty()) throw InputError(file.string(), "", "a .nii, .nii.gz, .nrrd, .nhdr, .mha, .mhd, .inr or .inr.gz file", file.extension().string());
  SliceStack s = kind == "nifti"       ? read_nifti(file)
                 : kind == "nrrd"      ? read_nrrd(file)
                 : kind == "metaimage" ? read_metaimage(file)
                                       : read_inrimage(file);
  s.files = 1;
  s.bit_depth = 0;
  return s;
}

}  // namespace tactus::segment
