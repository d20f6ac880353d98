#pragma once
// A synthetic CT of a human hand at the paper's scale (§3.1, §3.2: L1 = 159 mm wide, L2 = 230 mm
// long along the slice axis, L3 = 78 mm thick), with its ground truth. 27 bones as in the paper
// (8 carpals, 5 metacarpals, 14 phalanges, thumb with 2), each a cortical shell around a
// lower-density trabecular core, separated at the joints by soft-tissue gaps, inside a
// soft-tissue envelope with a skin layer; fingers slightly flexed towards the palm, each joint
// about its digit's own flexion axis through the proximal bone's head centre (skeleton).
// CT realism: Hounsfield values per tissue, partial-volume blur, Gaussian noise, seeded.
#include <cstdint>
#include <filesystem>
#include <string>

#include "tactus/core/skeleton.hpp"
#include "tactus/core/volume.hpp"

namespace tactus::samples {

struct PhantomParams {
  double voxel_mm = 0.7;      // in-plane pixel size (x, y)
  double slice_mm = 0.7;      // slice spacing (z, the hand's long axis)
  double noise_hu = 25.0;     // standard deviation of the additive noise
  double bias_hu = 0.0;       // amplitude of a smooth additive intensity bias (scanner drift, beam hardening)
  double blur_voxels = 0.6;   // partial-volume blur, Gaussian sigma in voxels
  double flexion_deg = 12.0;  // flexion of each finger joint towards the palm
  double margin_mm = 6.0;     // air around the hand
  std::uint64_t seed = 1;
};

// Hounsfield values of the phantom's tissues.
struct PhantomHu {
  static constexpr double air = -1000, soft_tissue = 40, skin = 90, trabecular = 350, cortical = 1500;
};

struct Phantom {
  Volume<std::int16_t> ct;     // HU
  Volume<std::uint8_t> truth;  // 0 air, 1 soft tissue (incl. skin), 2..28 bones
  LabelTable labels;           // id -> bone name
  Skeleton skeleton;           // the bones' parents and the joints it flexes about (joints.json)
};

Phantom make_hand_phantom(const PhantomParams& params);

// Writes the slice stack of docs/design.md: slice_NNNN.png (16-bit, stored = HU - rescale_intercept)
// and stack.json (spacing_mm, origin_mm, rescale_slope 1, rescale_intercept -1024, slices) into
// `folder` (created; the caller stages it: tactus-phantom writes through an OutputFolder).
void write_slice_stack(const Volume<std::int16_t>& ct, const std::filesystem::path& folder);

}  // namespace tactus::samples

namespace tactus::samples {

// A CT Image Storage series (one file per slice, IM_NNNN.dcm) of `ct`: explicit VR little
// endian, or compressed by GDCM (RLE lossless, JPEG lossless); stored = HU + 1024 unsigned with
// RescaleIntercept -1024, PixelSpacing, ImageOrientationPatient from the volume's direction (its
// first two columns; the third must be their cross product), ImagePositionPatient of each slice
// (origin + k dz along the normal), and the patient, study, series, frame-of-reference, equipment
// and SOP common attributes a CT image requires.
struct DicomSeriesOptions {
  std::string compression = "none";  // "none", "rle", "jpeg-lossless"
  std::string series_uid;            // empty: a new UID
  std::string study_uid;             // empty: a new UID
  std::string description = "tactus phantom";
  int series_number = 1;
};
void write_dicom_series(const Volume<std::int16_t>& ct, const std::filesystem::path& folder, const DicomSeriesOptions& options = {});

}  // namespace tactus::samples
