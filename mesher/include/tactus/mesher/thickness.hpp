#pragma once
// How thick each label is, and its parts too thin to mesh. A label thinner than its elements (a
// narrow gap between two surfaces, a thin shell) gets tets flattened across it, and the smallest of
// them sets the stable step. The mesher measures each label's thickness with an exact Euclidean
// distance transform (Felzenszwalb and Huttenlocher's lower envelope of parabolas, one pass per
// axis, anisotropic spacing); a label thinner than its cell size is then meshed with a finer size
// of its own (image_mesher.hpp, label_cell_size_mm), and with --min-thickness-mm the parts of a
// label thinner than that are given to their neighbours first.
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tactus/core/volume.hpp"
#include "tactus/mesher/image_mesher.hpp"

namespace tactus::mesher {

// Squared Euclidean distance (m^2) from every voxel of `box` (dims d, spacing h) to the nearest
// voxel whose `site` is set (+inf when there is none).
std::vector<double> squared_distance_to_sites(const std::vector<std::uint8_t>& site, const std::array<int, 3>& d, const std::array<double, 3>& h);

struct LabelThickness {
  std::size_t voxels = 0;
  // Twice the largest distance from a voxel of the label to the nearest voxel of its boundary (a
  // voxel with a face neighbour of another label, or on the volume's edge), plus the smallest
  // spacing: one voxel for a one-voxel sheet, 2r + 1 voxels for a ball of radius r voxels.
  double thickness_m = 0;
  std::array<double, 3> thickest_at{0, 0, 0};  // world position of the voxel furthest inside (m)
};

// Each non-zero label's thickness.
std::map<int, LabelThickness> label_thickness(const Volume<std::uint8_t>& labels);

struct ThinPart {
  int label = 0;
  std::size_t voxels = 0;             // moved out of the label
  std::map<int, std::size_t> into;    // to which labels, how many voxels
  std::array<double, 3> at{0, 0, 0};  // world position of one of its voxels (m)
};

// Gives every voxel of a non-zero label where no ball of diameter `min_thickness_m` fits inside
// the label (the label less its morphological opening by that ball) to the neighbouring label it
// shares the most faces with, non-zero labels first, in sweeps from the outside in; returns what
// moved, per label.
std::vector<ThinPart> absorb_thin_parts(Volume<std::uint8_t>& labels, double min_thickness_m);

// tactus-mesh's step before meshing: absorb_thin_parts at min_thickness_mm (0: none), then each
// label's thickness; a label thinner than its cell size gets a cell and facet size of a third of
// its thickness, at least a voxel (p.label_cell_size_mm), so a few elements fit across it. When
// every label is that thin the cell sizes are wrong for the volume: an InputError naming each
// label and its thickness (`file` names the volume). Returns what quality.json's thin_regions holds.
nlohmann::json fit_thin_labels(Volume<std::uint8_t>& labels, const LabelTable& table, ImageMeshParams& p, double min_thickness_mm,
                               const std::string& file);

}  // namespace tactus::mesher
