#include "tactus/segment/run.hpp"

#include <chrono>
#include <fstream>

#include "tactus/core/contracts.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/version.hpp"
#include "tactus/segment/dicom.hpp"
#include "tactus/segment/stack.hpp"
#include "tactus/segment/volume_files.hpp"

namespace fs = std::filesystem;

namespace tactus::segment {

namespace {

// How the labels came about: the imported values' mapping, or the thresholds and the steps.
void add_steps(nlohmann::json& j, const StageOptions& o, const Segmentation& s, const std::vector<ImportedLabel>& imported) {
  if (o.import_labels) {
    j["imported_labels"] = nlohmann::json::array();
    int tissue_value = 0;
    for (const auto& l : imported) {
      j["imported_labels"].push_back({{"value", l.value}, {"label", l.label}, {"name", l.name}, {"voxels", l.voxels}});
      if (l.label == contracts::kSoftTissueLabel) tissue_value = l.value;
    }
    j["steps"] = {"label volume imported: value 0 the background, value " + std::to_string(tissue_value) +
                  " the soft tissue (label 1), the other values labels 2.. in increasing order (imported_labels)"};
    return;
  }
  j["thresholds"] = {{"body_hu", s.body_threshold_hu},         {"body_source", s.body_threshold_source},   {"bone_hu", s.bone_threshold_hu},
                     {"bone_source", s.bone_threshold_source}, {"soft_tissue_level_hu", s.soft_tissue_hu}, {"cortical_level_hu", s.cortical_hu}};
  j["steps"] = {"3-D Gaussian denoise sigma " + std::to_string(o.segment.denoise_sigma_voxels) + " voxel",
                "body = largest 3-D component above the body threshold, holes filled",
                "bone = body voxels above the bone threshold, marrow holes filled (3-D and in the planes across each axis)",
                "bones split: 6-connected components of the mask eroded by " + std::to_string(o.segment.split_erosion_voxels) +
                    " voxel, grown back; touching pieces joined again when they touch across " + std::to_string(o.segment.split_neck_ratio) +
                    " of the smaller one's V^(2/3) or either kept less than " + std::to_string(o.segment.split_min_core_fraction) +
                    " of itself as its eroded core",
                "each bone closed by a box of half-width " + std::to_string(o.segment.marrow_closing_mm) + " mm (not into or next to another bone)",
                "bone components under " + std::to_string(o.segment.min_bone_volume_mm3) + " mm^3 removed"};
}

}  // namespace

nlohmann::json run_segment_stage(const fs::path& stack_folder, const fs::path& out, const StageOptions& o) {
  OutputFolder staged(out, {"tactus-segment", {stack_folder}, false});
  return run_segment_stage(stack_folder, staged, o);
}

nlohmann::json run_segment_stage(const fs::path& stack_folder, OutputFolder& staged, const StageOptions& o) {
  const fs::path out = staged.path();
  using Clock = std::chrono::steady_clock;
  auto seconds = [](Clock::time_point a) { return std::chrono::duration<double>(Clock::now() - a).count(); };
  const auto t0 = Clock::now();
  // A NIfTI, NRRD or MetaImage file; a folder with stack.json is a slice stack; one with DICOM
  // files (and no stack.json) a series.
  std::error_code ec;
  const bool file = fs::exists(stack_folder, ec) && !fs::is_directory(stack_folder, ec);
  if (file) require_regular_file(stack_folder, "a CT input (a slice stack folder, a DICOM folder or a volume file)");
  const bool dicom = !file && is_dicom_folder(stack_folder);
  if (!dicom && !o.dicom_series.empty())
    throw InputError(stack_folder.string(), "--series", "a folder of DICOM files (--series chooses among its series)", "another input");
  SliceStack stack = file ? read_volume_file(stack_folder) : dicom ? read_dicom_series(stack_folder, o.dicom_series) : read_slice_stack(stack_folder);
  const double t_read = seconds(t0);
  const auto t1 = Clock::now();
  const std::array<int, 3> dims = stack.hu.dims;
  const std::array<double, 3> spacing = stack.hu.spacing;
  const double voxel_volume = stack.hu.voxel_volume();
  std::vector<ImportedLabel> imported;
  const Segmentation s = o.import_labels ? import_label_volume(stack.hu, o.labels, stack_folder.string(), imported)
                                         : segment_hand(std::move(stack.hu), o.segment);  // the HU volume is not needed after
  const double t_segment = seconds(t1);

  write_h5(out / "labels.h5", "/labels", s.labels, &s.table);
  write_vti(out / "labels.vti", s.labels, "labels");

  nlohmann::json j;
  j["tactus_version"] = kVersion;
  j["stack"] = fs::absolute(stack_folder).string();
  j["units"] = "SI (m, m^3); thresholds in HU";
  j["dims"] = dims;
  j["spacing_m"] = spacing;
  j["bit_depth"] = stack.bit_depth;
  j["input"] = stack.source;
  add_steps(j, o, s, imported);
  j["body_volume_m3"] = static_cast<double>(s.body_voxels) * voxel_volume;
  j["bone_volume_m3"] = static_cast<double>(s.bone_voxels) * voxel_volume;
  j["specks_removed"] = s.specks_removed;
  j["bones"] = nlohmann::json::array();
  for (const auto& b : s.bones)
    j["bones"].push_back(
        {{"label", b.label}, {"name", s.table.at(b.label)}, {"voxels", b.voxels}, {"volume_m3", b.volume_m3}, {"centroid_m", b.centroid_m}});
  double t_surfaces = 0;
  std::vector<std::string> warnings;
  if (o.write_surfaces) {
    const auto t2 = Clock::now();
    const auto surfaces = extract_surfaces(s.labels, s.table, out / "surfaces", o.surfaces);
    t_surfaces = seconds(t2);
    j["surfaces"] = nlohmann::json::array();
    for (const auto& r : surfaces) {
      if (!r.passed) warnings.push_back(r.failure);
      nlohmann::json checks = {{"passed", r.passed},
                               {"closed", r.closed},
                               {"manifold", r.manifold},
                               {"self_intersecting", r.self_intersecting},
                               {"repairs_tried", r.repairs}};
      if (!r.passed) {
        checks["failed"] = r.failure;
        checks["self_intersecting_triangle_pairs"] = r.intersecting_pairs;
        if (r.intersecting_pairs > 0) checks["worst_self_intersection_m"] = r.worst_self_intersection;
      }
      j["surfaces"].push_back({{"name", r.name},
                               {"stl", r.stl.filename().string()},
                               {"ply", r.ply.filename().string()},
                               {"vertices", r.vertices},
                               {"triangles", r.triangles},
                               {"volume_m3", r.surface_volume_m3},
                               {"label_volume_m3", r.label_volume_m3},
                               {"area_m2", r.area_m2},
                               {"min_angle_deg", r.min_angle_deg},
                               {"closed", r.closed},
                               {"manifold", r.manifold},
                               {"self_intersecting", r.self_intersecting},
                               {"edge_factor", r.edge_factor},
                               {"checks", checks}});
    }
  }
  // "partial": the labels are whole, a surface is not (its file is <name>_failed_checks.stl); the
  // exit code stays 0, so the pipeline goes on to the mesher, which reads labels.h5.
  j["status"] = warnings.empty() ? "complete" : "partial";
  j["warnings"] = warnings;
  j["time_s"] = {{"read", t_read}, {"segment", t_segment}, {"surfaces", t_surfaces}};
  write_file(out / "segment.json", j.dump(2) + '\n');
  staged.commit();
  if (o.import_labels)
    log::info() << "segment: imported " << imported.size() - 1 << " label(s) of " << stack_folder.string() << "; wrote "
                << staged.final_path().string();
  else
    log::info() << "segment: " << s.bones.size() << " bones; thresholds body " << s.body_threshold_hu << " HU (" << s.body_threshold_source
                << "), bone " << s.bone_threshold_hu << " HU (" << s.bone_threshold_source << "); "
                << "read " << t_read << " s, segment " << t_segment << " s, surfaces " << t_surfaces << " s; wrote " << staged.final_path().string();
  return j;
}

}  // namespace tactus::segment
