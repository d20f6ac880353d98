#pragma once
// Segmentation of a hand CT into air (0), soft tissue (1) and individual bones (2..N):
// 3-D Gaussian denoising; a body threshold (given, or Otsu over the whole volume) keeping the
// largest 3-D component with its holes filled; a bone threshold (given, or halfway between the
// body's median HU (soft tissue) and its 99th percentile (cortical bone))
// whose marrow holes are filled in 3-D and per slice; specks removed by size; bones split at the joints by
// labelling the mask eroded by one voxel (6-connected components) and growing the labels back.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "tactus/core/volume.hpp"

namespace tactus::segment {

struct SegmentParams {
  std::optional<double> body_threshold_hu;  // default: Otsu on the whole volume (air vs tissue)
  std::optional<double> bone_threshold_hu;  // default: midpoint of the soft-tissue and cortical levels
  double denoise_sigma_voxels = 0.8;
  double min_bone_volume_mm3 = 30.0;  // smaller bone components are specks
  int split_erosion_voxels = 1;       // erosion that separates bones touching at a joint
  // Pieces of the split that touch across at least this fraction of the smaller piece's V^(2/3)
  // (its cross-section, in voxel faces) are one bone: a joint bridged by partial volume touches
  // through a narrow neck, a bone shattered by the erosion (thin bones on coarse voxels) across its
  // whole section.
  double split_neck_ratio = 0.5;
  // Touching pieces are joined too when the erosion left less than this fraction of either as its
  // core: a bone a few voxels across (a coarse scan) is cut where it is thinnest, not at a joint.
  double split_min_core_fraction = 0.3;
  // Each bone is closed (dilated, then eroded) by a box of this half-width: a marrow left open by
  // partial volume (a thin cortex across thick slices) is filled. Never into another bone or next
  // to one, so joint gaps stay. 0: off.
  double marrow_closing_mm = 1.5;
};

struct BoneInfo {
  int label = 0;
  std::size_t voxels = 0;
  double volume_m3 = 0;
  std::array<double, 3> centroid_m{0, 0, 0};
};

struct Segmentation {
  Volume<std::uint8_t> labels;
  LabelTable table;
  std::vector<BoneInfo> bones;
  double body_threshold_hu = 0, bone_threshold_hu = 0;
  double soft_tissue_hu = 0, cortical_hu = 0;                // levels the automatic bone threshold is the midpoint of
  std::string body_threshold_source, bone_threshold_source;  // "given" or "otsu"
  std::size_t body_voxels = 0, bone_voxels = 0, specks_removed = 0;
};

// `hu` is taken by value: pass an rvalue (std::move) when the caller no longer needs it, to save
// a copy of the largest array of the stage.
Segmentation segment_hand(Volume<float> hu, const SegmentParams& params);

// Otsu's threshold over values in [lo, hi] (256 bins), for `values` where `mask` is set (or all).
double otsu_threshold(const std::vector<float>& values, const std::vector<std::uint8_t>* mask, double lo, double hi);

}  // namespace tactus::segment
