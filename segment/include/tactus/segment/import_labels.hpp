#pragma once
// A label volume made elsewhere (a segmentation tool's output, an atlas) taken as tactus labels,
// without thresholds: its voxel values must be whole numbers. Value 0 is the background; one value
// is the soft tissue (label 1: the body the others lie in; by default the most common non-zero
// value), the other values become labels 2, 3, ... in increasing order, each its own region as a
// bone is. The mesher then meshes them as it meshes a segmented hand.
#include <map>
#include <string>
#include <vector>

#include "tactus/segment/segment.hpp"

namespace tactus::segment {

struct ImportedLabel {
  int value = 0;  // in the input
  int label = 0;  // in labels.h5
  std::string name;
  std::size_t voxels = 0;
};

struct LabelImport {
  int tissue_value = -1;             // the input value that becomes the soft tissue; -1: the most common non-zero one
  std::map<int, std::string> names;  // by input value; unnamed values are "label_<value>"
};

// `values` as read (any voxel type, as floats); `file` names it in errors. Fills `imported` with
// the mapping (background first).
Segmentation import_label_volume(const Volume<float>& values, const LabelImport& options, const std::string& file,
                                 std::vector<ImportedLabel>& imported);

}  // namespace tactus::segment
