#pragma once
// The segment stage as a whole: slice stack or DICOM series -> labels.h5, labels.vti, surfaces/,
// segment.json.
#include <filesystem>

#include <nlohmann/json.hpp>

#include "tactus/core/output.hpp"
#include "tactus/segment/import_labels.hpp"
#include "tactus/segment/segment.hpp"
#include "tactus/segment/surfaces.hpp"

namespace tactus::segment {

struct StageOptions {
  SegmentParams segment;
  SurfaceParams surfaces;
  bool write_surfaces = true;
  std::string dicom_series;    // a DICOM folder's SeriesInstanceUID (empty: its only series)
  bool import_labels = false;  // the input is a label volume (import_labels.hpp), not a CT
  LabelImport labels;
};

// Writes labels.h5, labels.vti, surfaces/ and segment.json into `out` and commits it; returns the
// report that is also written as segment.json.
nlohmann::json run_segment_stage(const std::filesystem::path& stack, OutputFolder& out, const StageOptions& options);
// The same into a new folder `out` (tests, benchmarks).
nlohmann::json run_segment_stage(const std::filesystem::path& stack, const std::filesystem::path& out, const StageOptions& options);

}  // namespace tactus::segment
