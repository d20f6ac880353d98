#pragma once
// How the segmented bones map onto the phantom's true bones: a true bone is shattered when more
// than one bone label holds over 10 % of its voxels, lost when none does.
#include <cstddef>
#include <map>

#include "tactus/core/volume.hpp"

namespace tactus::testkit {

struct BoneOverlap {
  std::size_t shattered = 0, lost = 0;
};

inline BoneOverlap bone_overlap(const Volume<std::uint8_t>& labels, const Volume<std::uint8_t>& truth) {
  std::map<int, std::map<int, std::size_t>> overlap;
  std::map<int, std::size_t> truth_voxels;
  for (std::size_t i = 0; i < labels.size(); ++i)
    if (truth.data[i] >= 2) ++truth_voxels[truth.data[i]], ++overlap[truth.data[i]][labels.data[i]];
  BoneOverlap o;
  for (const auto& [bone, by_label] : overlap) {
    int big = 0;
    for (const auto& [label, n] : by_label) big += label >= 2 && n > truth_voxels[bone] / 10;
    o.shattered += big > 1, o.lost += big == 0;
  }
  return o;
}

}  // namespace tactus::testkit
