// Node relocation (post_passes.hpp).
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

// Relocates the nodes of the tets with the smallest characteristic length L_e relative to their
// subdomain's median (these set the explicit time step). CGAL's perturb/exude leave them because
// all four nodes lie on surfaces (skin, bone interfaces). Each node of such a tet is moved by a
// pattern search that maximises the smallest L_e/median of its incident tets: interior nodes
// freely, surface nodes in their tangent plane and by at most `max_surface_move` (so the surface
// approximation is kept), nodes on a crease (adjacent surface normals > p.crease_angle_deg apart)
// not at all. A move is kept only if it does not bring any incident tet's dihedral angle below
// p.dihedral_floor_deg
// (or below its current value, if lower already).
void relocate_short_tets(TetMesh& mesh, double max_surface_move, const PostPassParams& p) {
  const double ratio_goal = p.relocate_ratio_goal;
  const int passes = p.relocate_passes;
  const std::size_t nn = mesh.nodes.size();
  const auto tets_of = tets_around_nodes(mesh);
  // Surface normals per node (area weighted) and crease detection.
  std::vector<std::array<double, 3>> normal(nn, {0, 0, 0});
  std::vector<char> on_surface(nn, 0), crease(nn, 0);
  std::vector<std::vector<std::array<double, 3>>> face_normals(nn);
  for (const auto& f : mesh.triangles) {
    const auto n = area_normal(mesh, f);
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (len == 0) continue;
    for (int v : f) {
      const auto k = static_cast<std::size_t>(v);
      on_surface[k] = 1;
      for (int i = 0; i < 3; ++i) normal[k][static_cast<std::size_t>(i)] += n[static_cast<std::size_t>(i)];
      face_normals[k].push_back({n[0] / len, n[1] / len, n[2] / len});
    }
  }
  for (std::size_t k = 0; k < nn; ++k) {
    if (!on_surface[k]) continue;
    const double len = std::sqrt(normal[k][0] * normal[k][0] + normal[k][1] * normal[k][1] + normal[k][2] * normal[k][2]);
    for (auto& x : normal[k]) x /= len;
    // Only unsigned agreement matters: a node on two touching surfaces has opposite normals.
    for (const auto& fnrm : face_normals[k])
      if (std::abs(fnrm[0] * normal[k][0] + fnrm[1] * normal[k][1] + fnrm[2] * normal[k][2]) < std::cos(p.crease_angle_deg * M_PI / 180))
        crease[k] = 1;
  }
  auto length = [&](std::size_t e) {
    const auto& t = mesh.tets[e];
    const TetGradients g = tet_shape_gradients(mesh.nodes[static_cast<std::size_t>(t[0])], mesh.nodes[static_cast<std::size_t>(t[1])],
                                               mesh.nodes[static_cast<std::size_t>(t[2])], mesh.nodes[static_cast<std::size_t>(t[3])]);
    return g.volume > 0 ? characteristic_length(g) : -1.0;
  };
  std::map<int, double> median;
  {
    std::map<int, std::vector<double>> per;
    for (std::size_t e = 0; e < mesh.tets.size(); ++e) per[mesh.tet_group[e]].push_back(length(e));
    for (auto& [g, v] : per) {
      std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
      median[g] = v[v.size() / 2];
    }
  }
  auto ratio = [&](std::size_t e) { return length(e) / median[mesh.tet_group[e]]; };
  auto worst_around = [&](std::size_t k) {
    double q = 1e300;
    for (std::size_t e : tets_of[k]) q = std::min(q, ratio(e));
    return q;
  };
  auto min_dihedral_around = [&](std::size_t k) {
    double a = 180;
    for (std::size_t e : tets_of[k]) {
      const auto& t = mesh.tets[e];
      a = std::min(a, tet_quality(mesh.nodes[static_cast<std::size_t>(t[0])], mesh.nodes[static_cast<std::size_t>(t[1])],
                                  mesh.nodes[static_cast<std::size_t>(t[2])], mesh.nodes[static_cast<std::size_t>(t[3])])
                          .min_dihedral_deg);
    }
    return a;
  };
  for (int pass = 0; pass < passes; ++pass) {
    std::set<std::size_t> nodes;
    for (std::size_t e = 0; e < mesh.tets.size(); ++e)
      if (ratio(e) < ratio_goal)
        for (int v : mesh.tets[e]) nodes.insert(static_cast<std::size_t>(v));
    if (nodes.empty()) break;
    for (std::size_t k : nodes) {
      if (crease[k]) continue;
      const Vec3 start = mesh.nodes[k];
      double best = worst_around(k);
      const double angle_floor = std::min(p.dihedral_floor_deg, min_dihedral_around(k));
      const double h = 0.5 * median[mesh.tet_group[tets_of[k].front()]];
      double step = 0.3 * h;
      Vec3 moved{0, 0, 0};
      for (int it = 0; it < p.relocate_iterations && step > 0.01 * h; ++it) {
        bool improved = false;
        for (int axis = 0; axis < 3 && !improved; ++axis)
          for (int sign = -1; sign <= 1 && !improved; sign += 2) {
            Vec3 d{0, 0, 0};
            d[static_cast<std::size_t>(axis)] = sign * step;
            if (on_surface[k]) {  // tangential only
              const double dn = d[0] * normal[k][0] + d[1] * normal[k][1] + d[2] * normal[k][2];
              for (int i = 0; i < 3; ++i) d[static_cast<std::size_t>(i)] -= dn * normal[k][static_cast<std::size_t>(i)];
            }
            const Vec3 trial_total{moved[0] + d[0], moved[1] + d[1], moved[2] + d[2]};
            if (on_surface[k] &&
                std::sqrt(trial_total[0] * trial_total[0] + trial_total[1] * trial_total[1] + trial_total[2] * trial_total[2]) > max_surface_move)
              continue;
            for (int i = 0; i < 3; ++i)
              mesh.nodes[k][static_cast<std::size_t>(i)] = start[static_cast<std::size_t>(i)] + trial_total[static_cast<std::size_t>(i)];
            const double q = worst_around(k);
            if (q > best * (1 + 1e-9) && min_dihedral_around(k) >= angle_floor) {
              best = q, moved = trial_total, improved = true;
            } else {
              for (int i = 0; i < 3; ++i)
                mesh.nodes[k][static_cast<std::size_t>(i)] = start[static_cast<std::size_t>(i)] + moved[static_cast<std::size_t>(i)];
            }
          }
        if (!improved) step *= 0.5;
      }
    }
  }
}

}  // namespace tactus::mesher
