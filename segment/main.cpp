// tactus-segment: CT (slice stack, DICOM series, NIfTI, NRRD, MetaImage) -> labels.h5/.vti (air, soft tissue, one id per bone),
// surfaces/*.stl|ply (skin and bones) and segment.json. Thin driver over tactus::segment.
#include <algorithm>
#include <cctype>

#include "tactus/core/cli.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/output.hpp"
#include "tactus/segment/run.hpp"

int main(int argc, char** argv) {
  using namespace tactus;
  CLI::App app{"tactus-segment: segment a hand CT (slice stack or DICOM series) into soft tissue and individual bones", "tactus-segment"};
  cli::CommonOptions common;
  cli::add_common_options(app, common, "output folder (labels.h5, labels.vti, surfaces/, segment.json)", "an output folder");
  std::string stack;
  segment::StageOptions o;
  double body = 0, bone = 0;
  bool no_surfaces = false;
  app.add_option("stack", stack,
                 "CT input: a slice stack folder (slice_NNNN.png|tif + stack.json), a folder of DICOM files, or a .nii/.nii.gz, .nrrd/.nhdr or "
                 ".mha/.mhd or .inr/.inr.gz file; with --labels a label volume in one of these file formats")
      ->required();
  app.add_option("--series", o.dicom_series, "SeriesInstanceUID of the DICOM series to read (a folder with several lists them)");
  auto* body_opt = app.add_option("--body-threshold", body, "HU separating air from the body (default: Otsu)");
  auto* bone_opt = app.add_option("--bone-threshold", bone, "HU separating soft tissue from bone (default: Otsu in the body)");
  app.add_option("--denoise", o.segment.denoise_sigma_voxels, "Gaussian denoising sigma, voxels")->capture_default_str();
  app.add_option("--min-bone-mm3", o.segment.min_bone_volume_mm3, "smallest bone kept, mm^3")->capture_default_str();
  app.add_option("--edge-voxels", o.surfaces.target_edge_voxels, "surface remeshing edge length, voxels")->capture_default_str();
  app.add_flag("--no-surfaces", no_surfaces, "skip surface extraction");
  bool labels_input = false;
  std::vector<std::string> label_names;
  app.add_flag("--labels", labels_input,
               "the input is a label volume made elsewhere (whole numbers: 0 background), not a CT: imported without thresholds, "
               "--tissue-label becoming the soft tissue (label 1) and the other values labels 2.. in increasing order");
  app.add_option("--tissue-label", o.labels.tissue_value, "with --labels: the value that is the soft tissue (default: the most common non-zero one)");
  app.add_option("--label-name", label_names, "with --labels: VALUE=NAME names an imported label (repeatable; default label_<value>)");
  bool no_repair = false;
  app.add_flag("--no-surface-repair", no_repair,
               "do not repair a surface that fails its checks (coarser remeshing, CGAL's local self-intersection removal, a smoothed "
               "label): it is written as <name>_failed_checks.stl at once; for the tests of that path");
  return cli::run(app, argc, argv, common, [&] {
    // Bounds a sigma, a volume and an edge can sensibly mean (finite numbers are checked by cli::run;
    // the sigma against the volume's extent once it is read, in segment_hand).
    if (o.segment.denoise_sigma_voxels < 0 || o.segment.denoise_sigma_voxels > 50)
      throw InputError("command line", "--denoise", "a Gaussian sigma of 0 (none) to 50 voxels", std::to_string(o.segment.denoise_sigma_voxels));
    if (o.segment.min_bone_volume_mm3 < 0)
      throw InputError("command line", "--min-bone-mm3", "a volume >= 0 mm^3", std::to_string(o.segment.min_bone_volume_mm3));
    if (o.surfaces.target_edge_voxels < 0.5 || o.surfaces.target_edge_voxels > 50)
      throw InputError("command line", "--edge-voxels", "a remeshing edge of 0.5 to 50 voxels (finer adds triangles, not detail)",
                       std::to_string(o.surfaces.target_edge_voxels));
    o.import_labels = labels_input;
    for (const std::string& n : label_names) {
      const auto eq = n.find('=');
      std::size_t used = 0;
      int value = -1;
      try {
        value = eq == std::string::npos ? -1 : std::stoi(n.substr(0, eq), &used);
      } catch (const std::exception&) {
      }
      const std::string name = eq == std::string::npos ? std::string() : n.substr(eq + 1);
      const bool plain =
          !name.empty() && std::all_of(name.begin(), name.end(), [](unsigned char c) { return std::isalnum(c) || c == '_' || c == '-'; });
      if (!labels_input || value < 0 || used != eq || !plain)
        throw InputError("command line", "--label-name", "VALUE=NAME with --labels (a whole value >= 0; a name of letters, digits, _ and -)", n);
      o.labels.names[value] = name;
    }
    if (*body_opt) o.segment.body_threshold_hu = body;
    if (*bone_opt) o.segment.bone_threshold_hu = bone;
    o.write_surfaces = !no_surfaces;
    o.surfaces.repair = !no_repair;
    OutputFolder out(common.output, common.output_rules({stack}));
    segment::run_segment_stage(stack, out, o);
  });
}
