#include "tactus/core/mesh.hpp"

#include <algorithm>

#include "tactus/core/error.hpp"

namespace tactus {

const PhysicalGroup* TetMesh::find_group(int dim, std::string_view name) const {
  for (const auto& g : groups)
    if (g.dim == dim && g.name == name) return &g;
  return nullptr;
}

const PhysicalGroup* TetMesh::find_group(int dim, int tag) const {
  for (const auto& g : groups)
    if (g.dim == dim && g.tag == tag) return &g;
  return nullptr;
}

double tet_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double e3[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  return (e1[0] * (e2[1] * e3[2] - e2[2] * e3[1]) - e1[1] * (e2[0] * e3[2] - e2[2] * e3[0]) + e1[2] * (e2[0] * e3[1] - e2[1] * e3[0])) / 6.0;
}

void TetMesh::validate(const std::string& source) const {
  if (tet_group.size() != tets.size())
    throw InputError(source, "tet groups", std::to_string(tets.size()) + " entries", std::to_string(tet_group.size()));
  if (triangle_group.size() != triangles.size())
    throw InputError(source, "triangle groups", std::to_string(triangles.size()) + " entries", std::to_string(triangle_group.size()));
  const int n = static_cast<int>(nodes.size());
  for (std::size_t e = 0; e < tets.size(); ++e) {
    for (int v : tets[e])
      if (v < 0 || v >= n)
        throw InputError(source, "tet " + std::to_string(e + 1), "node indices in [1, " + std::to_string(n) + "]", std::to_string(v + 1));
    if (!find_group(3, tet_group[e]))
      throw InputError(source, "tet " + std::to_string(e + 1), "a declared physical volume group", "tag " + std::to_string(tet_group[e]));
  }
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (int v : triangles[t])
      if (v < 0 || v >= n)
        throw InputError(source, "triangle " + std::to_string(t + 1), "node indices in [1, " + std::to_string(n) + "]", std::to_string(v + 1));
    if (!find_group(2, triangle_group[t]))
      throw InputError(source, "triangle " + std::to_string(t + 1), "a declared physical surface group", "tag " + std::to_string(triangle_group[t]));
  }
}

}  // namespace tactus
