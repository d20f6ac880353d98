#include "tactus/data_samples/box_mesh.hpp"

#include <algorithm>
#include <map>
#include <numeric>
#include <random>

namespace tactus::samples {

TetMesh make_box_mesh(int nx, int ny, int nz, double lx, double ly, double lz, Vec3 origin) {
  TetMesh m;
  auto id = [&](int i, int j, int k) { return i + (nx + 1) * (j + (ny + 1) * k); };
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) m.nodes.push_back({origin[0] + lx * i / nx, origin[1] + ly * j / ny, origin[2] + lz * k / nz});
  static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& p : perms) {
          int c[3] = {0, 0, 0};
          std::array<int, 4> t;
          t[0] = id(i, j, k);
          for (int s = 0; s < 3; ++s) {
            c[p[s]] = 1;
            t[s + 1] = id(i + c[0], j + c[1], k + c[2]);
          }
          if (tet_volume(m.nodes[t[0]], m.nodes[t[1]], m.nodes[t[2]], m.nodes[t[3]]) < 0) std::swap(t[2], t[3]);
          m.tets.push_back(t);
          m.tet_group.push_back(1);
        }
  m.groups.push_back({3, 1, "body"});
  const char* names[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
  for (int s = 0; s < 6; ++s) m.groups.push_back({2, 11 + s, names[s]});
  // Boundary faces: those used by exactly one tet; orient outward (away from the 4th node).
  std::map<std::array<int, 3>, std::pair<int, std::array<int, 4>>> faces;
  static const int fv[4][4] = {{1, 2, 3, 0}, {0, 3, 2, 1}, {0, 1, 3, 2}, {0, 2, 1, 3}};
  for (const auto& t : m.tets)
    for (const auto& f : fv) {
      std::array<int, 3> key = {t[f[0]], t[f[1]], t[f[2]]};
      std::sort(key.begin(), key.end());
      auto& entry = faces[key];
      entry.first++;
      entry.second = {t[f[0]], t[f[1]], t[f[2]], t[f[3]]};
    }
  const double lo[3] = {origin[0], origin[1], origin[2]};
  const double hi[3] = {origin[0] + lx, origin[1] + ly, origin[2] + lz};
  const double tol = 1e-9 * std::max({lx, ly, lz});
  for (const auto& [key, entry] : faces) {
    if (entry.first != 1) continue;
    const auto& f = entry.second;
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side) {
        const double plane = side ? hi[axis] : lo[axis];
        bool on = true;
        for (int v = 0; v < 3; ++v) on = on && std::abs(m.nodes[f[v]][axis] - plane) < tol;
        if (!on) continue;
        std::array<int, 3> tri = {f[0], f[1], f[2]};
        // Outward: the opposite vertex must lie on the negative side of the triangle.
        if (tet_volume(m.nodes[tri[0]], m.nodes[tri[1]], m.nodes[tri[2]], m.nodes[f[3]]) > 0) std::swap(tri[1], tri[2]);
        m.triangles.push_back(tri);
        m.triangle_group.push_back(11 + 2 * axis + side);
      }
  }
  return m;
}

void perturb_interior_nodes(TetMesh& mesh, double cell_size, double fraction, std::uint64_t seed) {
  Vec3 lo = mesh.nodes[0], hi = mesh.nodes[0];
  for (const auto& x : mesh.nodes)
    for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], x[c]), hi[c] = std::max(hi[c], x[c]);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-fraction * cell_size, fraction * cell_size);
  const double tol = 1e-9 * cell_size;
  for (auto& x : mesh.nodes) {
    bool interior = true;
    for (int c = 0; c < 3; ++c) interior = interior && x[c] > lo[c] + tol && x[c] < hi[c] - tol;
    if (interior)
      for (int c = 0; c < 3; ++c) x[c] += u(rng);
  }
}

void shuffle_numbering(TetMesh& mesh, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<int> perm(mesh.nodes.size());
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), rng);  // perm[old] = new
  std::vector<Vec3> nodes(mesh.nodes.size());
  for (std::size_t i = 0; i < perm.size(); ++i) nodes[perm[i]] = mesh.nodes[i];
  mesh.nodes = std::move(nodes);
  for (auto& t : mesh.tets)
    for (int& v : t) v = perm[v];
  for (auto& t : mesh.triangles)
    for (int& v : t) v = perm[v];
  std::vector<std::size_t> order(mesh.tets.size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng);
  std::vector<std::array<int, 4>> tets(order.size());
  std::vector<int> groups(order.size());
  for (std::size_t e = 0; e < order.size(); ++e) tets[e] = mesh.tets[order[e]], groups[e] = mesh.tet_group[order[e]];
  mesh.tets = std::move(tets);
  mesh.tet_group = std::move(groups);
}

void append_mesh(TetMesh& mesh, const TetMesh& other, int tag_offset, const std::string& name_suffix) {
  const int off = static_cast<int>(mesh.nodes.size());
  mesh.nodes.insert(mesh.nodes.end(), other.nodes.begin(), other.nodes.end());
  for (std::size_t e = 0; e < other.tets.size(); ++e) {
    auto t = other.tets[e];
    for (int& v : t) v += off;
    mesh.tets.push_back(t);
    mesh.tet_group.push_back(other.tet_group[e] + tag_offset);
  }
  for (std::size_t e = 0; e < other.triangles.size(); ++e) {
    auto t = other.triangles[e];
    for (int& v : t) v += off;
    mesh.triangles.push_back(t);
    mesh.triangle_group.push_back(other.triangle_group[e] + tag_offset);
  }
  for (auto g : other.groups) {
    g.tag += tag_offset;
    g.name += name_suffix;
    mesh.groups.push_back(g);
  }
}

}  // namespace tactus::samples
