#pragma once
// Scenarios built in memory for the solver tests, entry by entry as a scenario file declares them.
#include <array>
#include <string>

#include "tactus/core/mesh.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/scenario.hpp"
#include "temp_dir.hpp"

namespace tactus::testkit {

inline solver::MaterialInstance linear_elastic_instance(const std::string& name, double E, double nu, double density) {
  return solver::MaterialInstance{name, "linear_elastic", {{{"E", E}, {"nu", nu}, {"density", density}}, {}}};
}

// Writes `mesh` as <dir>/<name>.msh and returns a body of that name, made of `material` everywhere.
inline solver::BodySpec body_from_mesh(const TempDir& dir, const std::string& name, const TetMesh& mesh, const std::string& material) {
  solver::BodySpec b;
  b.name = name;
  b.mesh = dir.path() / (name + ".msh");
  write_msh(b.mesh, mesh);
  b.materials["*"] = material;
  return b;
}

// Adds a box mesh's whole boundary (its six face groups' triangles) as one more group, "surface" (20).
inline void add_whole_boundary_group(TetMesh& box) {
  box.groups.push_back({2, 20, "surface"});
  for (std::size_t t = 0, n = box.triangles.size(); t < n; ++t) box.triangles.push_back(box.triangles[t]), box.triangle_group.push_back(20);
}

// A [[boundary]] entry: `type` (fixed, velocity, displacement) on `components` of a body's group.
inline solver::BoundarySpec boundary(const std::string& body, const std::string& group, solver::BoundaryType type, std::array<bool, 3> components,
                                     const std::string& name) {
  solver::BoundarySpec b;
  b.body = body, b.group = group, b.type = type, b.components = components, b.name = name;
  return b;
}

// Advances a quasi-static run until, after t_min, its kinetic energy is below `ratio` of its
// strain energy (or the run ends); stops after a velocity update, as the solver reports.
inline void run_to_rest(solver::ExplicitSolver& s, double t_min, double ratio) {
  while (true) {
    s.advance_velocity();
    if (s.finished() || (s.time() > t_min && s.energies().kinetic <= ratio * s.energies().internal)) break;
    s.advance_position();
  }
}

}  // namespace tactus::testkit
