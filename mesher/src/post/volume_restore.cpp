// Volume restore (post_passes.hpp).
#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "tactus/core/contracts.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/stable_step.hpp"
#include "tactus/mesher/post_passes.hpp"
#include "tactus/mesher/quality.hpp"

namespace tactus::mesher {

// The mesher's surfaces are chords of the labelled image's (trilinear, corner-cutting) boundary,
// so convex bones come out 3-4 % below their voxel volume. Restore each closed surface's volume
// (every bone's interface, and the skin for the whole body) with one offset along the vertex
// normals, delta = (V_label - V_mesh) / area, a fraction of a millimetre; halve it for a surface
// whose move would invert a tet.
void restore_volumes(TetMesh& mesh, const Volume<std::uint8_t>& labels, const std::vector<int>& triangle_inner, const PostPassParams& p) {
  std::map<int, double> target;  // 0: whole body
  for (auto v : labels.data)
    if (v) target[v] += labels.voxel_volume(), target[0] += labels.voxel_volume();
  const auto tets_of = tets_around_nodes(mesh);
  auto tet_vol = [&](std::size_t e) {
    const auto& t = mesh.tets[e];
    return tet_volume(mesh.nodes[static_cast<std::size_t>(t[0])], mesh.nodes[static_cast<std::size_t>(t[1])],
                      mesh.nodes[static_cast<std::size_t>(t[2])], mesh.nodes[static_cast<std::size_t>(t[3])]);
  };
  std::map<int, double> current;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    const double v = tet_vol(e);
    current[mesh.tet_group[e]] += v, current[0] += v;
  }
  for (const auto& [surface, goal] : target) {
    if (surface == contracts::kSoftTissueLabel) continue;  // soft tissue follows from the body and the bones
    std::map<int, std::array<double, 3>> normal;
    double area = 0;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      if (triangle_inner[t] != surface) continue;
      const auto& f = mesh.triangles[t];
      const auto n = area_normal(mesh, f);
      area += std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (int v : f)
        for (std::size_t k = 0; k < 3; ++k) normal[v][k] += n[k];
    }
    if (area <= 0) continue;
    double delta = (goal - current[surface]) / area;
    std::vector<std::pair<int, Vec3>> original;
    for (auto& [v, n] : normal) {
      const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (double& x : n) x /= len;
      original.emplace_back(v, mesh.nodes[static_cast<std::size_t>(v)]);
    }
    for (int attempt = 0; attempt < p.volume_restore_attempts; ++attempt, delta *= 0.5) {
      for (const auto& [v, x] : original)
        for (int k = 0; k < 3; ++k)
          mesh.nodes[static_cast<std::size_t>(v)][static_cast<std::size_t>(k)] =
              x[static_cast<std::size_t>(k)] + delta * normal[v][static_cast<std::size_t>(k)];
      bool valid = true;
      for (const auto& [v, x] : original)
        for (std::size_t e : tets_of[static_cast<std::size_t>(v)]) valid = valid && tet_vol(e) > 0;
      if (valid) break;
      for (const auto& [v, x] : original) mesh.nodes[static_cast<std::size_t>(v)] = x;
    }
  }
}

}  // namespace tactus::mesher
