// tactus-phantom: writes a synthetic hand CT, a slice stack (slice_NNNN.png + stack.json) or a
// DICOM series (IM_NNNN.dcm), and its ground truth (truth.h5, truth.vti, and joints.json: the
// skeleton its bones are built from) into the output folder.
#include <chrono>

#include "tactus/core/cli.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/output.hpp"
#include "tactus/data_samples/phantom.hpp"

int main(int argc, char** argv) {
  using namespace tactus;
  CLI::App app{"tactus-phantom: synthetic CT of a hand (27 bones, soft tissue, skin) with ground truth", "tactus-phantom"};
  cli::CommonOptions common;
  cli::add_common_options(app, common, "output folder (slices, stack.json, truth.h5)", "an output folder");
  samples::PhantomParams p;
  app.add_option("--voxel-mm", p.voxel_mm, "in-plane pixel size in mm (the paper: 0.7)")->capture_default_str();
  app.add_option("--slice-mm", p.slice_mm, "slice spacing in mm")->capture_default_str();
  app.add_option("--noise", p.noise_hu, "noise standard deviation in HU")->capture_default_str();
  app.add_option("--bias", p.bias_hu, "amplitude of a smooth intensity bias across the volume, HU")->capture_default_str();
  app.add_option("--blur", p.blur_voxels, "partial-volume blur, Gaussian sigma in voxels")->capture_default_str();
  app.add_option("--flexion", p.flexion_deg, "flexion of each finger joint, degrees")->capture_default_str();
  app.add_option("--seed", p.seed, "noise seed")->capture_default_str();
  std::string format = "png";
  samples::DicomSeriesOptions dicom;
  app.add_option("--format", format, "png: slice_NNNN.png + stack.json; dicom: a CT Image Storage series IM_NNNN.dcm")
      ->check(CLI::IsMember({"png", "dicom"}))
      ->capture_default_str();
  app.add_option("--dicom-compression", dicom.compression, "DICOM transfer syntax: none (explicit VR little endian), rle, jpeg-lossless")
      ->check(CLI::IsMember({"none", "rle", "jpeg-lossless"}))
      ->capture_default_str();
  app.add_option("--series-uid", dicom.series_uid, "DICOM SeriesInstanceUID (default: a new one)");
  app.add_option("--series-description", dicom.description, "DICOM SeriesDescription")->capture_default_str();
  return cli::run(app, argc, argv, common, [&] {
    const auto t0 = std::chrono::steady_clock::now();
    OutputFolder out(common.output, common.output_rules({}));
    const samples::Phantom ph = samples::make_hand_phantom(p);
    if (format == "dicom")
      samples::write_dicom_series(ph.ct, out.path(), dicom);
    else
      samples::write_slice_stack(ph.ct, out.path());
    write_h5(out.path() / "truth.h5", "/labels", ph.truth, &ph.labels);
    write_vti(out.path() / "truth.vti", ph.truth, "labels");
    write_skeleton(out.path() / "joints.json", ph.skeleton);
    out.commit();
    log::info() << "phantom: " << ph.ct.dims[0] << " x " << ph.ct.dims[1] << " x " << ph.ct.dims[2] << " voxels (" << p.voxel_mm << " x "
                << p.voxel_mm << " x " << p.slice_mm << " mm), " << ph.labels.size() - 2 << " bones, written to " << common.output << " in "
                << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s";
  });
}
