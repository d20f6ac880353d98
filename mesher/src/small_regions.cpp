#include "tactus/mesher/small_regions.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace tactus::mesher {

std::size_t min_region_voxels(const Volume<std::uint8_t>& labels, double min_volume_mm3, double bone_cell_size_mm) {
  const double mm3 = min_volume_mm3 > 0 ? min_volume_mm3 : std::pow(bone_cell_size_mm, 3) / 5;
  const double voxel_mm3 = labels.voxel_volume() * 1e9;
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(mm3 / voxel_mm3)));
}

std::vector<AbsorbedRegion> absorb_small_regions(Volume<std::uint8_t>& labels, std::size_t min_voxels) {
  std::vector<AbsorbedRegion> absorbed;
  const auto& d = labels.dims;
  const std::size_t n = labels.size(), sx = 1, sy = static_cast<std::size_t>(d[0]), sz = sy * static_cast<std::size_t>(d[1]);
  std::vector<std::int32_t> region(n);
  std::vector<std::size_t> stack, members;
  for (int sweep = 0; sweep < 4; ++sweep) {
    std::fill(region.begin(), region.end(), -1);
    std::size_t changed = 0;
    std::int32_t next = 0;
    for (std::size_t seed = 0; seed < n; ++seed) {
      if (region[seed] >= 0) continue;
      const std::uint8_t value = labels.data[seed];
      const std::int32_t id = next++;
      members.clear();
      stack.assign(1, seed);
      region[seed] = id;
      bool border = false;
      std::map<int, std::size_t> faces;  // neighbour label -> shared voxel faces
      while (!stack.empty()) {
        const std::size_t v = stack.back();
        stack.pop_back();
        members.push_back(v);
        const int x = static_cast<int>(v % sy), y = static_cast<int>((v / sy) % static_cast<std::size_t>(d[1])), z = static_cast<int>(v / sz);
        if (x == 0 || y == 0 || z == 0 || x == d[0] - 1 || y == d[1] - 1 || z == d[2] - 1) border = true;
        const std::size_t step[3] = {sx, sy, sz};
        const int coord[3] = {x, y, z};
        for (int a = 0; a < 3; ++a)
          for (int side = -1; side <= 1; side += 2) {
            const int c = coord[a] + side;
            if (c < 0 || c >= d[static_cast<std::size_t>(a)]) continue;
            const std::size_t w = side < 0 ? v - step[a] : v + step[a];
            if (labels.data[w] == value) {
              if (region[w] < 0) region[w] = id, stack.push_back(w);
            } else {
              ++faces[labels.data[w]];
            }
          }
      }
      if (members.size() >= min_voxels || faces.empty() || (value == 0 && border)) continue;
      const auto best = std::max_element(faces.begin(), faces.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
      AbsorbedRegion r;
      r.label = value, r.voxels = members.size(), r.into = best->first;
      r.at = labels.voxel_world(members.front());
      for (std::size_t m : members) labels.data[m] = static_cast<std::uint8_t>(best->first);
      absorbed.push_back(r);
      ++changed;
    }
    if (changed == 0) break;
  }
  return absorbed;
}

}  // namespace tactus::mesher
