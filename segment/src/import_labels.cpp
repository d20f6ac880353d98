#include "tactus/segment/import_labels.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "tactus/core/contracts.hpp"
#include "tactus/core/error.hpp"

namespace tactus::segment {

Segmentation import_label_volume(const Volume<float>& values, const LabelImport& options, const std::string& file,
                                 std::vector<ImportedLabel>& imported) {
  // Counts per value; a fraction or a value past uint16 is not a label (a CT passed by mistake).
  std::map<int, std::size_t> count;
  const std::size_t nx = static_cast<std::size_t>(values.dims[0]), ny = static_cast<std::size_t>(values.dims[1]);
  for (std::size_t i = 0; i < values.size(); ++i) {
    const float v = values.data[i];
    if (!(v >= 0 && v <= 65535 && v == std::floor(v))) {
      std::ostringstream at;
      at << v << " at voxel (" << i % nx << ", " << i / nx % ny << ", " << i / (nx * ny) << ")";
      throw InputError(file, "voxels", "whole label numbers from 0 to 65535 (a label volume, not a CT: drop --labels for a CT)", at.str());
    }
    ++count[static_cast<int>(v)];
  }
  const std::size_t background = count[contracts::kBackgroundLabel];
  count.erase(contracts::kBackgroundLabel);
  if (count.empty()) throw InputError(file, "voxels", "at least one non-zero label", "only background (0)");
  if (count.size() > 254) throw InputError(file, "voxels", "at most 254 distinct non-zero labels", std::to_string(count.size()));
  int tissue = options.tissue_value;
  if (tissue < 0) {
    tissue = count.begin()->first;
    for (const auto& [v, n] : count)
      if (n > count.at(tissue)) tissue = v;
  } else if (!count.count(tissue)) {
    throw InputError(file, "--tissue-label", "a value the volume holds", std::to_string(tissue));
  }
  for (const auto& [v, name] : options.names)
    if (!count.count(v)) throw InputError(file, "--label-name", "a value the volume holds", std::to_string(v) + "=" + name);

  Segmentation s;
  s.labels = values.like<std::uint8_t>();
  s.body_threshold_source = s.bone_threshold_source = "imported";
  s.table[contracts::kBackgroundLabel] = "background";
  imported.clear();
  imported.push_back({0, contracts::kBackgroundLabel, "background", background});
  std::map<int, int> label_of{{0, contracts::kBackgroundLabel}};
  int next = contracts::kFirstBoneLabel;
  for (const auto& [v, n] : count) {
    const int label = v == tissue ? contracts::kSoftTissueLabel : next++;
    auto named = options.names.find(v);
    const std::string name = named != options.names.end()           ? named->second
                             : label == contracts::kSoftTissueLabel ? std::string(contracts::kSoftTissueName)
                                                                    : "label_" + std::to_string(v);
    s.table[label] = name;
    label_of[v] = label;
    imported.push_back({v, label, name, n});
    s.body_voxels += n;
    if (label != contracts::kSoftTissueLabel) s.bone_voxels += n;
  }
  std::map<int, std::array<double, 4>> sums;  // per label >= 2: the voxel centres' sum and count
  for (int k = 0; k < values.dims[2]; ++k)
    for (int j = 0; j < values.dims[1]; ++j)
      for (int i = 0; i < values.dims[0]; ++i) {
        const auto idx = values.index(i, j, k);
        const int label = label_of.at(static_cast<int>(values.data[idx]));
        s.labels.data[idx] = static_cast<std::uint8_t>(label);
        if (label >= contracts::kFirstBoneLabel) {
          auto& a = sums[label];
          a[0] += i, a[1] += j, a[2] += k, a[3] += 1;
        }
      }
  for (const auto& [label, a] : sums) {
    BoneInfo b;
    b.label = label;
    b.voxels = static_cast<std::size_t>(a[3]);
    b.volume_m3 = a[3] * values.voxel_volume();
    b.centroid_m = values.to_world({values.origin[0] + a[0] / a[3] * values.spacing[0], values.origin[1] + a[1] / a[3] * values.spacing[1],
                                    values.origin[2] + a[2] / a[3] * values.spacing[2]});
    s.bones.push_back(b);
  }
  return s;
}

}  // namespace tactus::segment
