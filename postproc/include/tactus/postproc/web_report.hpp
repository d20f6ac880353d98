#pragma once
// The interactive report: report/index.html, a self-contained page (three.js vendored beside it,
// the data in <script> files under report/data/, so it opens from the file system without a
// server) showing the bodies' boundary surface at every output state with a time slider, the
// contact pressure, von Mises (nodal average or per tet) and displacement on fixed colour
// scales, node picking and the history plots.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "tactus/core/vec3.hpp"
#include "tactus/postproc/results.hpp"
#include "tactus/postproc/summary.hpp"

namespace tactus::postproc {

struct WebReportOptions {
  // The page and its data stay below this many bytes: when the full boundary surface would not,
  // the part that never touches anything is coarsened by vertex clustering until it does.
  std::size_t byte_budget = 45u << 20;
  bool page = true;          // index.html and data/; off: only the pressure tables
  std::vector<Vec3> probes;  // points (m, reference configuration) whose nearest surface node's pressure goes to probes.csv
};

struct WebReport {
  std::vector<std::string> files;                  // written, relative to the report folder
  std::size_t bytes = 0;                           // their total size
  std::size_t surface_faces = 0, faces_shown = 0;  // boundary triangles of the bodies, and those drawn
  std::vector<std::string> missing;                // what the page says it could not show, and why
};

// The colour scale's top for a field sampled as (value, weight) pairs: the smallest value with
// 99.5 % of the total weight at or below it (pressure_scale_cap's rule), here on a logarithmic
// histogram so that the tets of every output state need not be held at once: `add` them, then
// `cap()` is at most one bin (a factor 10^(1/400), 0.58 %) above the exact weighted percentile.
class PercentileCap {
 public:
  void add(double value, double weight);
  double cap() const;
  double peak() const { return peak_; }

 private:
  static constexpr int kBinsPerDecade = 400, kLowestDecade = -3, kDecades = 16;
  std::vector<double> weight_ = std::vector<double>(static_cast<std::size_t>(kBinsPerDecade * kDecades), 0.0);
  double total_ = 0, peak_ = 0;
};

// Also writes, whatever the options: pressure_<ms>ms.csv for each output with contact (the
// pressed nodes: node_id, current x y z, pressure, friction traction, tributary area, body), and
// probes.csv (the pressure against time at the surface node nearest each probe point).
WebReport write_web_report(const Results& results, const Summary& summary, const std::filesystem::path& report, const WebReportOptions& options = {});

}  // namespace tactus::postproc
