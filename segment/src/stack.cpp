#include "tactus/segment/stack.hpp"

#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>

#include "tactus/core/error.hpp"
#include "tactus/core/progress.hpp"

namespace fs = std::filesystem;

namespace tactus::segment {

namespace {

std::array<double, 3> read_vec3(const nlohmann::json& j, const std::string& key, const std::string& file, bool required,
                                bool positive) {
  if (!j.contains(key)) {
    if (required) throw InputError(file, key, "[x, y, z] in mm", "missing");
    return {0, 0, 0};
  }
  const auto& v = j[key];
  if (!v.is_array() || v.size() != 3) throw InputError(file, key, "an array of 3 numbers [x, y, z] in mm", v.dump());
  std::array<double, 3> out{};
  for (int i = 0; i < 3; ++i) {
    if (!v[i].is_number()) throw InputError(file, key, "numbers", v.dump());
    out[i] = v[i].get<double>();
    if (positive && !(out[i] > 0)) throw InputError(file, key, "positive spacings in mm", v.dump());
  }
  return out;
}

}  // namespace

SliceStack read_slice_stack(const fs::path& folder) {
  const std::string dir = folder.string();
  if (!fs::is_directory(folder)) throw InputError(dir, "", "a folder with slice_NNNN.png|tif and stack.json", "no such folder");
  const fs::path meta_file = folder / "stack.json";
  if (!fs::exists(meta_file))
    throw InputError(meta_file.string(), "", "a stack.json with spacing_mm, origin_mm, rescale_slope, rescale_intercept",
                     "missing");
  std::ifstream in(meta_file);
  const nlohmann::json meta = nlohmann::json::parse(in, nullptr, false);
  if (meta.is_discarded() || !meta.is_object()) throw InputError(meta_file.string(), "", "a JSON object", "malformed JSON");
  const auto spacing = read_vec3(meta, "spacing_mm", meta_file.string(), true, true);
  const auto origin = read_vec3(meta, "origin_mm", meta_file.string(), false, false);
  auto number = [&](const char* key, double def) {
    if (!meta.contains(key)) return def;
    if (!meta[key].is_number()) throw InputError(meta_file.string(), key, "a number", meta[key].dump());
    return meta[key].get<double>();
  };
  const double slope = number("rescale_slope", 1.0), intercept = number("rescale_intercept", 0.0);
  if (slope == 0) throw InputError(meta_file.string(), "rescale_slope", "a non-zero number", "0");

  // Slices by number; the numbering must be contiguous.
  const std::regex pattern(R"(slice_(\d+)\.(png|tif|tiff))", std::regex::icase);
  std::map<long, fs::path> slices;
  for (const auto& entry : fs::directory_iterator(folder)) {
    std::smatch m;
    const std::string name = entry.path().filename().string();
    if (std::regex_match(name, m, pattern)) {
      const long k = std::stol(m[1].str());
      if (!slices.emplace(k, entry.path()).second)
        throw InputError(dir, name, "one file per slice number", "slice " + m[1].str() + " twice");
    }
  }
  if (slices.empty()) throw InputError(dir, "", "slice_NNNN.png or slice_NNNN.tif files", "none");
  long expected = slices.begin()->first;
  for (const auto& [k, path] : slices) {
    if (k != expected)
      throw InputError(dir, "slice " + std::to_string(expected), "contiguous slice numbers",
                       "slice " + std::to_string(expected) + " missing (next is " + path.filename().string() + ")");
    ++expected;
  }

  SliceStack out;
  out.files = slices.size();
  int nx = 0, ny = 0;
  const int nz = static_cast<int>(slices.size());
  Progress progress("read slices", slices.size());
  int k = 0;
  for (const auto& [num, path] : slices) {
    const cv::Mat img = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
    if (img.empty()) throw InputError(path.string(), "", "a readable 8- or 16-bit PNG/TIFF image", "unreadable");
    if (img.channels() != 1) throw InputError(path.string(), "", "a single-channel (grey) image", std::to_string(img.channels()) + " channels");
    if (img.depth() != CV_8U && img.depth() != CV_16U) throw InputError(path.string(), "", "8- or 16-bit unsigned pixels", "another pixel type");
    const int depth = img.depth() == CV_8U ? 8 : 16;
    if (k == 0) {
      nx = img.cols, ny = img.rows, out.bit_depth = depth;
      out.hu = Volume<float>({nx, ny, nz}, {spacing[0] * 1e-3, spacing[1] * 1e-3, spacing[2] * 1e-3},
                             {origin[0] * 1e-3, origin[1] * 1e-3, origin[2] * 1e-3});
    } else if (img.cols != nx || img.rows != ny) {
      throw InputError(path.string(), "", std::to_string(nx) + " x " + std::to_string(ny) + " pixels like the first slice",
                       std::to_string(img.cols) + " x " + std::to_string(img.rows));
    } else if (depth != out.bit_depth) {
      throw InputError(path.string(), "", std::to_string(out.bit_depth) + "-bit pixels like the first slice", std::to_string(depth) + "-bit");
    }
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const double stored = depth == 8 ? img.at<std::uint8_t>(j, i) : img.at<std::uint16_t>(j, i);
        out.hu.at(i, j, k) = static_cast<float>(slope * stored + intercept);
      }
    progress.update(static_cast<std::size_t>(++k));
  }
  progress.finish();
  return out;
}

}  // namespace tactus::segment
