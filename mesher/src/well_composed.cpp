#include "tactus/mesher/well_composed.hpp"

#include <algorithm>

#include "post/topology.hpp"

namespace tactus::mesher {

namespace {

// The 2 x 2 x 2 block with its lowest corner at (x, y, z): corner k = (k & 1, k >> 1 & 1, k >> 2 & 1).
struct Block {
  std::array<std::uint8_t, 8> v;
};

Block block_at(const Volume<std::uint8_t>& L, int x, int y, int z) {
  Block b;
  for (int k = 0; k < 8; ++k) b.v[static_cast<std::size_t>(k)] = L.at(x + (k & 1), y + (k >> 1 & 1), z + (k >> 2 & 1));
  return b;
}

// The six faces of a block as 2 x 2 squares (a, b, c, d with a-d and b-c the diagonals).
constexpr std::array<std::array<int, 4>, 6> kFaces{{{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 4, 5}, {2, 3, 6, 7}, {0, 2, 4, 6}, {1, 3, 5, 7}}};

// A mask of the block: label `v` (v >= 1), or every label >= 1 (v = 0: the skin's).
template <class Count>
void for_each_mask(const Block& b, Count count) {
  std::array<std::uint8_t, 8> seen{};
  std::size_t n = 0;
  bool any = false;
  for (std::uint8_t v : b.v) {
    any = any || v != 0;
    if (v != 0 && std::find(seen.begin(), seen.begin() + static_cast<std::ptrdiff_t>(n), v) == seen.begin() + static_cast<std::ptrdiff_t>(n))
      seen[n++] = v;
  }
  if (!any) return;
  for (std::size_t i = 0; i < n; ++i) count([&](int k) { return b.v[static_cast<std::size_t>(k)] == seen[i]; });
  if (n > 1 || std::count(b.v.begin(), b.v.end(), 0) > 0) count([&](int k) { return b.v[static_cast<std::size_t>(k)] != 0; });
}

// Edge and vertex pinches of one block over its masks. The faces are shared with the neighbouring
// blocks, so a volume's total counts each edge pinch twice where both blocks exist; comparisons of
// the same neighbourhood before and after a change are what the repair uses.
std::pair<std::size_t, std::size_t> block_pinches(const Block& b) {
  if (std::all_of(b.v.begin(), b.v.end(), [&](std::uint8_t v) { return v == b.v[0]; })) return {0, 0};
  std::size_t edges = 0, vertices = 0;
  for_each_mask(b, [&](auto in) {
    for (const auto& f : kFaces) edges += in(f[0]) == in(f[3]) && in(f[1]) == in(f[2]) && in(f[0]) != in(f[1]);
    for (int p = 0; p < 4; ++p) {  // opposite corners p and 7 - p
      const bool m = in(p);
      bool rest = true;
      for (int k = 0; k < 8 && rest; ++k)
        if (k != p && k != 7 - p) rest = in(k) != m;
      vertices += in(7 - p) == m && rest;
    }
  });
  return {edges, vertices};
}

// Pinches of the 8 blocks holding voxel (x, y, z).
std::size_t pinches_around(const Volume<std::uint8_t>& L, int x, int y, int z) {
  std::size_t n = 0;
  for (int dz = -1; dz <= 0; ++dz)
    for (int dy = -1; dy <= 0; ++dy)
      for (int dx = -1; dx <= 0; ++dx) {
        const int bx = x + dx, by = y + dy, bz = z + dz;
        if (bx < 0 || by < 0 || bz < 0 || bx + 1 >= L.dims[0] || by + 1 >= L.dims[1] || bz + 1 >= L.dims[2]) continue;
        const auto [e, v] = block_pinches(block_at(L, bx, by, bz));
        n += e + v;
      }
  return n;
}

}  // namespace

std::pair<std::size_t, std::size_t> count_critical_configurations(const Volume<std::uint8_t>& L) {
  std::size_t edges = 0, vertices = 0;
  for (int z = 0; z + 1 < L.dims[2]; ++z)
    for (int y = 0; y + 1 < L.dims[1]; ++y)
      for (int x = 0; x + 1 < L.dims[0]; ++x) {
        const auto [e, v] = block_pinches(block_at(L, x, y, z));
        edges += e, vertices += v;
      }
  return {edges, vertices};
}

WellComposedReport make_well_composed(Volume<std::uint8_t>& L) {
  WellComposedReport r;
  std::tie(r.edge_pinches, r.vertex_pinches) = count_critical_configurations(L);
  if (r.edge_pinches + r.vertex_pinches == 0) return r;
  for (int sweep = 0; sweep < 8; ++sweep) {
    bool changed = false;
    for (int z = 0; z + 1 < L.dims[2]; ++z)
      for (int y = 0; y + 1 < L.dims[1]; ++y)
        for (int x = 0; x + 1 < L.dims[0]; ++x) {
          const Block b = block_at(L, x, y, z);
          const auto [e, v] = block_pinches(b);
          if (e + v == 0) continue;
          // Every single-voxel change of the block to a label it holds; the one that leaves the
          // fewest pinches around the voxel (fewer than before), a label before the background.
          std::size_t best = 0;
          int best_k = -1;
          std::uint8_t best_to = 0;
          for (int k = 0; k < 8; ++k) {
            const int vx = x + (k & 1), vy = y + (k >> 1 & 1), vz = z + (k >> 2 & 1);
            std::uint8_t& voxel = L.at(vx, vy, vz);
            const std::uint8_t was = voxel;
            const std::size_t before = pinches_around(L, vx, vy, vz);
            std::array<std::uint8_t, 8> candidates = b.v;
            std::sort(candidates.begin(), candidates.end(), std::greater<>());  // labels first, background last
            for (std::size_t c = 0; c < 8; ++c) {
              const std::uint8_t to = candidates[c];
              if (to == was || (c > 0 && to == candidates[c - 1])) continue;
              voxel = to;
              const std::size_t after = pinches_around(L, vx, vy, vz);
              if (after < before && before - after > best) best = before - after, best_k = k, best_to = to;
            }
            voxel = was;
          }
          if (best_k < 0) continue;
          const std::array<int, 3> at{x + (best_k & 1), y + (best_k >> 1 & 1), z + (best_k >> 2 & 1)};
          std::uint8_t& voxel = L.at(at[0], at[1], at[2]);
          r.changes.push_back({at, voxel, best_to});
          voxel = best_to;
          changed = true;
        }
    if (!changed) break;
  }
  r.voxels_changed = r.changes.size();
  const auto [e, v] = count_critical_configurations(L);
  r.remaining = e + v;
  return r;
}

std::map<std::string, BoundaryTopology> boundary_topology(const TetMesh& mesh) {
  // Each face (sorted node triple) with the tets holding it.
  std::map<std::array<int, 3>, std::vector<std::size_t>> face_tets;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e)
    for (int skip = 0; skip < 4; ++skip) {
      std::array<int, 3> f;
      for (int k = 0, i = 0; k < 4; ++k)
        if (k != skip) f[static_cast<std::size_t>(i++)] = mesh.tets[e][static_cast<std::size_t>(k)];
      std::sort(f.begin(), f.end());
      face_tets[f].push_back(e);
    }
  std::map<std::string, std::vector<std::array<int, 3>>> boundaries;
  auto group_name = [&](int tag) {
    const auto* g = mesh.find_group(3, tag);
    return g ? g->name : std::to_string(tag);
  };
  for (const auto& [f, tets] : face_tets) {
    if (tets.size() == 1) boundaries["skin"].push_back(f);
    const int a = mesh.tet_group[tets[0]];
    if (tets.size() == 1 || mesh.tet_group[tets[1]] != a) boundaries[group_name(a)].push_back(f);
    if (tets.size() == 2 && mesh.tet_group[tets[1]] != a) boundaries[group_name(mesh.tet_group[tets[1]])].push_back(f);
  }
  std::map<std::string, BoundaryTopology> out;
  for (const auto& [name, faces] : boundaries) {
    BoundaryTopology& t = out[name];
    t.faces = faces.size();
    std::map<std::pair<int, int>, std::size_t> edges;
    std::map<int, std::vector<std::size_t>> vertex_faces;
    for (std::size_t i = 0; i < faces.size(); ++i) {
      const auto& f = faces[i];
      for (int k = 0; k < 3; ++k) {
        ++edges[{std::min(f[static_cast<std::size_t>(k)], f[static_cast<std::size_t>((k + 1) % 3)]),
                 std::max(f[static_cast<std::size_t>(k)], f[static_cast<std::size_t>((k + 1) % 3)])}];
        vertex_faces[f[static_cast<std::size_t>(k)]].push_back(i);
      }
    }
    bool located = false;
    auto locate = [&](int node) {
      if (!located) t.first_defect = mesh.nodes[static_cast<std::size_t>(node)], located = true;
    };
    for (const auto& [e, n] : edges)
      if (n != 2) ++t.non_manifold_edges, locate(e.first);
    // A vertex's faces in one fan: joined through the edges they share at the vertex.
    for (const auto& [v, fs] : vertex_faces) {
      std::vector<std::array<int, 3>> at;
      for (std::size_t i : fs) at.push_back(faces[i]);
      const std::vector<std::size_t> fan = face_fans(at);
      const std::size_t fans = *std::max_element(fan.begin(), fan.end()) + 1;
      if (fans > 1) ++t.non_manifold_vertices, locate(v);
    }
  }
  return out;
}

}  // namespace tactus::mesher
