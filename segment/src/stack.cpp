#include "tactus/segment/stack.hpp"
#include "tactus/core/file_io.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>

#include "tactus/core/error.hpp"
#include "tactus/core/isolated.hpp"
#include "tactus/core/progress.hpp"

namespace fs = std::filesystem;

namespace tactus::segment {

namespace {

using nlohmann::json;

// A required (or optional, with default) number of stack.json: finite and in [lo, hi].
double json_number(const json& meta, const char* key, const std::string& file, std::optional<double> def, double lo, double hi,
                   const std::string& meaning) {
  if (!meta.contains(key)) {
    if (def) return *def;
    throw InputError(file, key, meaning, "missing");
  }
  const auto& v = meta[key];
  if (!v.is_number() || !std::isfinite(v.get<double>()) || v.get<double>() < lo || v.get<double>() > hi)
    throw InputError(file, key, meaning, v.dump().substr(0, 60));
  return v.get<double>();
}

std::array<double, 3> json_vec3(const json& meta, const char* key, const std::string& file, bool required, double lo, double hi,
                                const std::string& meaning) {
  if (!meta.contains(key)) {
    if (required) throw InputError(file, key, meaning, "missing");
    return {0, 0, 0};
  }
  const auto& v = meta[key];
  if (!v.is_array() || v.size() != 3) throw InputError(file, key, meaning, v.dump().substr(0, 60));
  std::array<double, 3> out{};
  for (int i = 0; i < 3; ++i) {
    if (!v[i].is_number() || !std::isfinite(v[i].get<double>()) || v[i].get<double>() < lo || v[i].get<double>() > hi)
      throw InputError(file, key, meaning, v.dump().substr(0, 60));
    out[i] = v[i].get<double>();
  }
  return out;
}

// CRC-32 of PNG chunks (ISO 3309 polynomial, as zlib's).
std::uint32_t crc32(const unsigned char* p, std::size_t n, std::uint32_t crc = 0) {
  static const auto table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (std::size_t i = 0; i < n; ++i) crc = table[(crc ^ p[i]) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

std::uint32_t be32(const unsigned char* p) { return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3]; }

// The PNG container is checked before a decoder sees it: signature, every chunk's length and
// CRC, a grey 8- or 16-bit IHDR of sane size, image data, and the end chunk.
void validate_png(const fs::path& path) {
  const std::string file = path.string();
  require_regular_file(path, "a slice image (PNG)");
  std::ifstream in(path, std::ios::binary);
  const std::string b((std::istreambuf_iterator<char>(in)), {});
  const auto* u = reinterpret_cast<const unsigned char*>(b.data());
  static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (b.size() < 8 || std::memcmp(u, sig, 8) != 0) throw InputError(file, "", "a PNG image", "no PNG signature (unreadable)");
  std::size_t pos = 8;
  bool header = false, data = false, end = false;
  while (pos + 12 <= b.size() && !end) {
    const std::uint32_t len = be32(u + pos);
    const std::string type = b.substr(pos + 4, 4);
    if (len > b.size() - pos - 12) throw InputError(file, "chunk " + type, "a chunk inside the file", "cut short (truncated)");
    if (crc32(u + pos + 4, len + 4) != be32(u + pos + 8 + len))
      throw InputError(file, "chunk " + type, "a chunk with a valid CRC", "a corrupt chunk");
    if (!header && type != "IHDR") throw InputError(file, "", "the IHDR chunk first", type);
    if (type == "IHDR") {
      if (header || len != 13) throw InputError(file, "IHDR", "one 13-byte IHDR chunk");
      header = true;
      const std::uint32_t w = be32(u + pos + 8), h = be32(u + pos + 12);
      const int depth = u[pos + 16], colour = u[pos + 17];
      if (w == 0 || h == 0 || w > static_cast<std::uint32_t>(kMaxVolumeDim) || h > static_cast<std::uint32_t>(kMaxVolumeDim))
        throw InputError(file, "IHDR", "1 to 65536 pixels per side", std::to_string(w) + " x " + std::to_string(h));
      if (colour != 0) throw InputError(file, "IHDR", "a single-channel (grey) image", "colour type " + std::to_string(colour));
      if (depth != 8 && depth != 16) throw InputError(file, "IHDR", "8- or 16-bit pixels", std::to_string(depth) + "-bit");
    }
    if (type == "IDAT") data = true;
    if (type == "IEND") end = true;
    pos += 12 + len;
  }
  if (!header || !data || !end) throw InputError(file, "", "a complete PNG image", "no image data or no end (truncated)");
}

void validate_tiff(const fs::path& path) {
  require_regular_file(path, "a slice image (TIFF)");
  std::ifstream in(path, std::ios::binary);
  char head[4] = {};
  in.read(head, 4);
  const bool le = std::memcmp(head, "II*\0", 4) == 0, be = std::memcmp(head, "MM\0*", 4) == 0;
  if (!le && !be) throw InputError(path.string(), "", "a TIFF image", "no TIFF header (unreadable)");
}

// Slice numbers from file names, without exceptions: an absurd number is an error, not a crash.
std::map<std::uint64_t, fs::path> list_slices(const fs::path& folder) {
  const std::string dir = folder.string();
  const std::regex pattern(R"(slice_(\d+)\.(png|tif|tiff))", std::regex::icase);
  std::map<std::uint64_t, fs::path> slices;
  for (const auto& entry : fs::directory_iterator(folder)) {
    std::smatch m;
    const std::string name = entry.path().filename().string();
    if (!std::regex_match(name, m, pattern)) continue;
    const std::string digits = m[1].str();
    std::uint64_t k = 0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), k);
    if (ec != std::errc() || end != digits.data() + digits.size() || k > 99999999)
      throw InputError(dir, name, "a slice number of at most 8 digits' value (0 to 99999999)", digits.substr(0, 30));
    if (!slices.emplace(k, entry.path()).second) throw InputError(dir, name, "one file per slice number", "slice " + digits + " twice");
  }
  return slices;
}

// Runs f with stderr closed: libpng and libtiff print their own complaints about corrupt data,
// which tactus reports once, in its own words.
template <class F>
auto quietly(F&& f) {
  std::fflush(stderr);
  const int saved = dup(STDERR_FILENO);
  const int null = open("/dev/null", O_WRONLY);
  if (null >= 0) dup2(null, STDERR_FILENO), close(null);
  auto result = f();
  std::fflush(stderr);
  if (saved >= 0) dup2(saved, STDERR_FILENO), close(saved);
  return result;
}

}  // namespace

SliceStack read_slice_stack(const fs::path& folder) {
  const std::string dir = folder.string();
  if (!fs::is_directory(folder)) throw InputError(dir, "", "a folder with slice_NNNN.png|tif and stack.json", "no such folder");
  const fs::path meta_file = folder / "stack.json";
  const std::string mf = meta_file.string();
  const std::string fields = "spacing_mm, rescale_slope, rescale_intercept and slices";
  std::error_code ec;
  if (!fs::exists(meta_file, ec)) throw InputError(mf, "", "a stack.json with " + fields, "missing");
  require_regular_file(meta_file, "a stack.json with " + fields);
  if (fs::file_size(meta_file, ec) > (1u << 20)) throw InputError(mf, "", "a stack.json of at most 1 MB", "a larger file");
  std::ifstream in(meta_file);
  const json meta = json::parse(in, nullptr, false);
  if (meta.is_discarded() || !meta.is_object()) throw InputError(mf, "", "a JSON object", "malformed JSON");
  // Geometry in mm (the DICOM convention), converted to metres once, here.
  const auto spacing = json_vec3(meta, "spacing_mm", mf, true, 1e-4, 1e3, "[x, y, z]: positive voxel sizes in mm (0.0001 to 1000)");
  const auto origin = json_vec3(meta, "origin_mm", mf, false, -1e6, 1e6, "[x, y, z] in mm, finite (within 1 km)");
  // The rescale is required: without the intercept, stored values are not Hounsfield units and
  // the thresholds find the wrong tissue (seen: 1 bone found instead of 5).
  const double slope =
      json_number(meta, "rescale_slope", mf, std::nullopt, -1e6, 1e6, "a non-zero number: HU = rescale_slope * stored + rescale_intercept");
  if (slope == 0) throw InputError(mf, "rescale_slope", "a non-zero number", "0");
  const double intercept =
      json_number(meta, "rescale_intercept", mf, std::nullopt, -1e6, 1e6, "a number: HU = rescale_slope * stored + rescale_intercept (e.g. -1024)");
  // The slice count catches a missing first or last slice, which the numbering cannot.
  const double declared = json_number(meta, "slices", mf, std::nullopt, 1, kMaxVolumeDim, "the number of slice files (an integer >= 1)");
  if (declared != std::floor(declared)) throw InputError(mf, "slices", "an integer", meta["slices"].dump());

  const auto slices = list_slices(folder);
  if (slices.empty()) throw InputError(dir, "", "slice_NNNN.png or slice_NNNN.tif files", "none");
  std::uint64_t expected = slices.begin()->first;
  for (const auto& [k, path] : slices) {
    if (k != expected)
      throw InputError(dir, "slice " + std::to_string(expected), "contiguous slice numbers",
                       "slice " + std::to_string(expected) + " missing (next is " + path.filename().string() + ")");
    ++expected;
  }
  if (slices.size() != static_cast<std::size_t>(declared))
    throw InputError(dir, "slices", std::to_string(static_cast<long long>(declared)) + " slice files as stack.json says",
                     std::to_string(slices.size()) + " (slice_" + std::to_string(slices.begin()->first) + " to slice_" +
                         std::to_string(slices.rbegin()->first) + "; a first or last slice missing?)");
  for (const auto& [k, path] : slices) {
    const std::string ext = path.extension().string();
    if (ext == ".png" || ext == ".PNG")
      validate_png(path);
    else
      validate_tiff(path);
  }

  // The image decoders (libpng, libtiff through OpenCV) run in an isolated child process; the
  // stored pixels come back and become HU here.
  const int nz = static_cast<int>(slices.size());
  const std::string bytes = run_isolated(
      dir, "slice image",
      [&](ByteWriter& w) {
        int nx = 0, ny = 0, depth = 0;
        std::vector<std::uint16_t> stored;
        Progress progress("read slices", slices.size());
        int k = 0;
        for (const auto& [num, path] : slices) {
          const cv::Mat img = quietly([&] { return cv::imread(path.string(), cv::IMREAD_UNCHANGED); });
          if (img.empty()) throw InputError(path.string(), "", "a readable 8- or 16-bit PNG/TIFF image", "unreadable");
          if (img.channels() != 1) throw InputError(path.string(), "", "a single-channel (grey) image", std::to_string(img.channels()) + " channels");
          if (img.depth() != CV_8U && img.depth() != CV_16U)
            throw InputError(path.string(), "", "8- or 16-bit unsigned pixels", "another pixel type");
          const int d = img.depth() == CV_8U ? 8 : 16;
          if (k == 0) {
            nx = img.cols, ny = img.rows, depth = d;
            validate_volume_geometry({nx, ny, nz}, {spacing[0] * 1e-3, spacing[1] * 1e-3, spacing[2] * 1e-3},
                                     {origin[0] * 1e-3, origin[1] * 1e-3, origin[2] * 1e-3}, sizeof(float) + sizeof(std::uint16_t), dir,
                                     "slice stack");
            stored.resize(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny) * static_cast<std::size_t>(nz));
          } else if (img.cols != nx || img.rows != ny) {
            throw InputError(path.string(), "", std::to_string(nx) + " x " + std::to_string(ny) + " pixels like the first slice",
                             std::to_string(img.cols) + " x " + std::to_string(img.rows));
          } else if (d != depth) {
            throw InputError(path.string(), "", std::to_string(depth) + "-bit pixels like the first slice", std::to_string(d) + "-bit");
          }
          std::uint16_t* out = stored.data() + static_cast<std::size_t>(k) * static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
          for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) out[j * nx + i] = d == 8 ? img.at<std::uint8_t>(j, i) : img.at<std::uint16_t>(j, i);
          progress.update(static_cast<std::size_t>(++k));
        }
        progress.finish();
        w.put(nx), w.put(ny), w.put(depth);
        w.put_vector(stored);
      },
      IsolationLimits{30.0 + 0.5 * static_cast<double>(slices.size()), 0});
  ByteReader r(bytes);
  SliceStack out;
  const int nx = r.get<int>(), ny = r.get<int>();
  out.bit_depth = r.get<int>();
  out.files = slices.size();
  const std::vector<std::uint16_t> stored = r.get_vector<std::uint16_t>();
  out.hu =
      Volume<float>({nx, ny, nz}, {spacing[0] * 1e-3, spacing[1] * 1e-3, spacing[2] * 1e-3}, {origin[0] * 1e-3, origin[1] * 1e-3, origin[2] * 1e-3});
  if (stored.size() != out.hu.size()) throw InputError(dir, "", "slices of one size", "a malformed read");
  for (std::size_t i = 0; i < stored.size(); ++i) out.hu.data[i] = static_cast<float>(slope * stored[i] + intercept);
  return out;
}

}  // namespace tactus::segment
