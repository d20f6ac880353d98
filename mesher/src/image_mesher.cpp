#include "tactus/mesher/image_mesher.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Image_3.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_constant_domain_field_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Mesh_3/initialize_triangulation_from_labeled_image.h>
#include <CGAL/make_mesh_3.h>
#include <CGAL/refine_mesh_3.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/stable_step.hpp"
#include "tactus/mesher/quality.hpp"

namespace tactus::mesher {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Domain = CGAL::Labeled_mesh_domain_3<K>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr>;
using Criteria = CGAL::Mesh_criteria_3<Tr>;
using SizeField = CGAL::Mesh_constant_domain_field_3<Domain::R, Domain::Index>;

void check(bool ok, const std::string& field, const std::string& expected, double value) {
  if (!ok) {
    std::ostringstream f;
    f << value;
    throw InputError("mesh criteria", field, expected, f.str());
  }
}

// The tets around every node.
std::vector<std::vector<std::size_t>> tets_around_nodes(const TetMesh& mesh) {
  std::vector<std::vector<std::size_t>> tets_of(mesh.nodes.size());
  for (std::size_t e = 0; e < mesh.tets.size(); ++e)
    for (int v : mesh.tets[e]) tets_of[static_cast<std::size_t>(v)].push_back(e);
  return tets_of;
}

// Half the cross product of a triangle's edges: its normal (orientation of the triangle) with
// length equal to its area.
std::array<double, 3> area_normal(const TetMesh& mesh, const std::array<int, 3>& f) {
  const Vec3 &a = mesh.nodes[static_cast<std::size_t>(f[0])], &b = mesh.nodes[static_cast<std::size_t>(f[1])],
             &c = mesh.nodes[static_cast<std::size_t>(f[2])];
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  return {0.5 * (u[1] * w[2] - u[2] * w[1]), 0.5 * (u[2] * w[0] - u[0] * w[2]), 0.5 * (u[0] * w[1] - u[1] * w[0])};
}

// The mesher's surfaces are chords of the labelled image's (trilinear, corner-cutting) boundary,
// so convex bones come out 3-4 % below their voxel volume. Restore each closed surface's volume
// (every bone's interface, and the skin for the whole body) with one offset along the vertex
// normals, delta = (V_label - V_mesh) / area, a fraction of a millimetre; halve it for a surface
// whose move would invert a tet.
void restore_volumes(TetMesh& mesh, const Volume<std::uint8_t>& labels, const std::vector<int>& triangle_inner) {
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
    if (surface == 1) continue;  // soft tissue follows from the body and the bones
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
    for (int attempt = 0; attempt < 4; ++attempt, delta *= 0.5) {
      for (const auto& [v, x] : original)
        for (int k = 0; k < 3; ++k) mesh.nodes[static_cast<std::size_t>(v)][static_cast<std::size_t>(k)] = x[static_cast<std::size_t>(k)] + delta * normal[v][static_cast<std::size_t>(k)];
      bool valid = true;
      for (const auto& [v, x] : original)
        for (std::size_t e : tets_of[static_cast<std::size_t>(v)]) valid = valid && tet_vol(e) > 0;
      if (valid) break;
      for (const auto& [v, x] : original) mesh.nodes[static_cast<std::size_t>(v)] = x;
    }
  }
}

// Relocates the nodes of the tets with the smallest characteristic length L_e relative to their
// subdomain's median (these set the explicit time step). CGAL's perturb/exude leave them because
// all four nodes lie on surfaces (skin, bone interfaces). Each node of such a tet is moved by a
// pattern search that maximises the smallest L_e/median of its incident tets: interior nodes
// freely, surface nodes in their tangent plane and by at most `max_surface_move` (so the surface
// approximation is kept), nodes on a crease (adjacent surface normals > 50 deg apart) not at all.
// A move is kept only if it does not bring any incident tet's dihedral angle below 10 degrees
// (or below its current value, if lower already).
void relocate_short_tets(TetMesh& mesh, double ratio_goal, double max_surface_move, int passes) {
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
      if (std::abs(fnrm[0] * normal[k][0] + fnrm[1] * normal[k][1] + fnrm[2] * normal[k][2]) < std::cos(50.0 * M_PI / 180)) crease[k] = 1;
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
                                           mesh.nodes[static_cast<std::size_t>(t[2])], mesh.nodes[static_cast<std::size_t>(t[3])]).min_dihedral_deg);
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
      const double angle_floor = std::min(10.0, min_dihedral_around(k));
      const double h = 0.5 * median[mesh.tet_group[tets_of[k].front()]];
      double step = 0.3 * h;
      Vec3 moved{0, 0, 0};
      for (int it = 0; it < 24 && step > 0.01 * h; ++it) {
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
            if (on_surface[k] && std::sqrt(trial_total[0] * trial_total[0] + trial_total[1] * trial_total[1] + trial_total[2] * trial_total[2]) >
                                     max_surface_move)
              continue;
            for (int i = 0; i < 3; ++i) mesh.nodes[k][static_cast<std::size_t>(i)] = start[static_cast<std::size_t>(i)] + trial_total[static_cast<std::size_t>(i)];
            const double q = worst_around(k);
            if (q > best * (1 + 1e-9) && min_dihedral_around(k) >= angle_floor) {
              best = q, moved = trial_total, improved = true;
            } else {
              for (int i = 0; i < 3; ++i) mesh.nodes[k][static_cast<std::size_t>(i)] = start[static_cast<std::size_t>(i)] + moved[static_cast<std::size_t>(i)];
            }
          }
        if (!improved) step *= 0.5;
      }
    }
  }
}


std::array<int, 3> sorted_face(int a, int b, int c) {
  std::array<int, 3> f{a, b, c};
  std::sort(f.begin(), f.end());
  return f;
}
constexpr int kFaces[4][4] = {{1, 2, 3, 0}, {0, 2, 3, 1}, {0, 1, 3, 2}, {0, 1, 2, 3}};  // face nodes, then the opposite

// Boundary triangles from the tets' labels: the faces between different labels (0 = outside),
// skin where one side is outside, bone interface otherwise; oriented out of the higher label
// (soft tissue under the skin, the bone at an interface), as CGAL's facets are above.
void rebuild_boundary_triangles(TetMesh& mesh) {
  std::map<std::array<int, 3>, std::vector<std::size_t>> owners;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e)
    for (const auto& f : kFaces) owners[sorted_face(mesh.tets[e][f[0]], mesh.tets[e][f[1]], mesh.tets[e][f[2]])].push_back(e);
  mesh.triangles.clear();
  mesh.triangle_group.clear();
  for (const auto& [key, tets] : owners) {
    const int la = mesh.tet_group[tets[0]], lb = tets.size() > 1 ? mesh.tet_group[tets[1]] : 0;
    if (la == lb) continue;
    const std::size_t inner = tets.size() > 1 && lb > la ? tets[1] : tets[0];
    const auto& t = mesh.tets[inner];
    int apex = 0;
    for (int v : t)
      if (v != key[0] && v != key[1] && v != key[2]) apex = v;
    std::array<int, 3> tri = key;
    if (tet_volume(mesh.nodes[static_cast<std::size_t>(tri[0])], mesh.nodes[static_cast<std::size_t>(tri[1])],
                   mesh.nodes[static_cast<std::size_t>(tri[2])], mesh.nodes[static_cast<std::size_t>(apex)]) > 0)
      std::swap(tri[1], tri[2]);  // the apex behind the triangle: its normal points out of `inner`
    mesh.triangles.push_back(tri);
    mesh.triangle_group.push_back(std::min(la, lb) == 0 ? kSkinTag : kBoneInterfaceTag);
  }
}

// Peels soft-tissue tets that lie flat on the skin (two or three faces on it) and whose
// characteristic length is below ratio_goal of the soft-tissue median: such a tet is a sliver of
// the surface approximation (its four nodes on the skin, e.g. at the wrist cut's rim or over a
// thin finger), no node can be moved to fix it without leaving the surface, and it sets the
// explicit time step. Removing it exposes its inner faces; the skin stays closed and 2-manifold
// (checked around every edge and node of the tet), every node stays in the mesh, and the volume
// lost is the sliver's (a fraction of a per mille). Returns the number of tets removed.
std::size_t peel_skin_slivers(TetMesh& mesh, double ratio_goal) {
  constexpr int kSoft = 1;
  auto length = [&](std::size_t e) {
    const auto& t = mesh.tets[e];
    const TetGradients g = tet_shape_gradients(mesh.nodes[static_cast<std::size_t>(t[0])], mesh.nodes[static_cast<std::size_t>(t[1])],
                                               mesh.nodes[static_cast<std::size_t>(t[2])], mesh.nodes[static_cast<std::size_t>(t[3])]);
    return g.volume > 0 ? characteristic_length(g) : 0.0;
  };
  std::vector<double> soft;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e)
    if (mesh.tet_group[e] == kSoft) soft.push_back(length(e));
  if (soft.empty()) return 0;
  std::nth_element(soft.begin(), soft.begin() + static_cast<std::ptrdiff_t>(soft.size() / 2), soft.end());
  const double median = soft[soft.size() / 2];

  std::map<std::array<int, 3>, std::vector<std::size_t>> owners;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e)
    for (const auto& f : kFaces) owners[sorted_face(mesh.tets[e][f[0]], mesh.tets[e][f[1]], mesh.tets[e][f[2]])].push_back(e);
  std::vector<char> alive(mesh.tets.size(), 1);
  const auto tets_of = tets_around_nodes(mesh);
  auto live_owners = [&](const std::array<int, 3>& key) {
    std::size_t n = 0;
    for (std::size_t e : owners[key]) n += alive[e];
    return n;
  };
  // Skin faces (one live soft-tissue owner, nothing behind) around a node, among its live tets.
  auto skin_faces_at = [&](int node) {
    std::set<std::array<int, 3>> out;
    for (std::size_t e : tets_of[static_cast<std::size_t>(node)]) {
      if (!alive[e]) continue;
      for (const auto& f : kFaces) {
        const auto key = sorted_face(mesh.tets[e][f[0]], mesh.tets[e][f[1]], mesh.tets[e][f[2]]);
        if ((key[0] == node || key[1] == node || key[2] == node) && live_owners(key) == 1 && mesh.tet_group[e] != 0) out.insert(key);
      }
    }
    return out;
  };
  // One closed fan of faces around the node, each edge of it shared by exactly two faces.
  auto manifold_at = [&](int node) {
    const auto faces = skin_faces_at(node);
    if (faces.empty()) return true;
    std::map<int, std::vector<std::array<int, 3>>> by_edge;  // other end of the edge at `node`
    for (const auto& f : faces)
      for (int v : f)
        if (v != node) by_edge[v].push_back(f);
    for (const auto& [v, fs] : by_edge)
      if (fs.size() != 2) return false;
    std::set<std::array<int, 3>> seen{*faces.begin()};
    std::vector<std::array<int, 3>> stack{*faces.begin()};
    while (!stack.empty()) {
      const auto f = stack.back();
      stack.pop_back();
      for (int v : f)
        if (v != node)
          for (const auto& g : by_edge[v])
            if (seen.insert(g).second) stack.push_back(g);
    }
    return seen.size() == faces.size();
  };

  std::vector<std::pair<double, std::size_t>> candidates;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e)
    if (mesh.tet_group[e] == kSoft && length(e) < ratio_goal * median) candidates.push_back({length(e), e});
  std::sort(candidates.begin(), candidates.end());
  std::size_t removed = 0;
  for (const auto& [len, e] : candidates) {
    const auto& t = mesh.tets[e];
    int on_skin = 0;
    bool ok = true;
    for (const auto& f : kFaces) {
      const auto key = sorted_face(t[f[0]], t[f[1]], t[f[2]]);
      const std::size_t n = live_owners(key);
      if (n == 1) {
        ++on_skin;
      } else {
        for (std::size_t other : owners[key])  // the face becomes skin: only over soft tissue
          if (other != e && alive[other] && mesh.tet_group[other] != kSoft) ok = false;
      }
    }
    log::debug() << "peel: tet " << e << " L/median " << len / median << ", " << on_skin << " faces on the skin, faces over soft tissue " << ok;
    if (!ok || on_skin < 1) continue;  // one face on the skin: only with a neighbour (below)
    for (int v : t) {  // every node keeps a tet
      std::size_t n = 0;
      for (std::size_t o : tets_of[static_cast<std::size_t>(v)]) n += alive[o] && o != e;
      ok = ok && n > 0;
    }
    if (!ok) continue;
    alive[e] = 0;
    for (int v : t) ok = ok && manifold_at(v);
    log::debug() << "peel: tet " << e << " nodes kept; manifold after removal " << ok;
    if (ok) {
      ++removed;
      continue;
    }
    // Alone it would pinch the skin (e.g. across the sharp rim of the wrist cut): try it together
    // with one soft-tissue neighbour that is short too.
    bool paired = false;
    for (const auto& f : kFaces) {
      if (paired) break;
      for (std::size_t other : owners[sorted_face(t[f[0]], t[f[1]], t[f[2]])]) {
        if (other == e || !alive[other] || mesh.tet_group[other] != kSoft || length(other) >= 1.5 * ratio_goal * median) continue;
        bool behind_soft = true;  // the pair's faces that become skin lie over soft tissue
        for (const auto& g : kFaces)
          for (std::size_t o : owners[sorted_face(mesh.tets[other][g[0]], mesh.tets[other][g[1]], mesh.tets[other][g[2]])])
            behind_soft = behind_soft && (o == e || o == other || !alive[o] || mesh.tet_group[o] == kSoft);
        if (!behind_soft) continue;
        alive[other] = 0;
        bool good = true;
        for (const std::array<int, 4>* tet : {&t, static_cast<const std::array<int, 4>*>(&mesh.tets[other])})
          for (int v : *tet) {
            std::size_t n = 0;
            for (std::size_t o : tets_of[static_cast<std::size_t>(v)]) n += alive[o];
            good = good && n > 0 && manifold_at(v);
          }
        if (good) {
          paired = true;
          removed += 2;
          break;
        }
        alive[other] = 1;
      }
    }
    if (!paired) alive[e] = 1;
  }
  if (removed == 0) return 0;
  std::vector<std::array<int, 4>> tets;
  std::vector<int> groups;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e)
    if (alive[e]) tets.push_back(mesh.tets[e]), groups.push_back(mesh.tet_group[e]);
  mesh.tets = std::move(tets);
  mesh.tet_group = std::move(groups);
  rebuild_boundary_triangles(mesh);
  return removed;
}

}  // namespace

double expected_tets(const Volume<std::uint8_t>& labels, const ImageMeshParams& p) {
  std::size_t soft = 0, bone = 0;
  for (auto v : labels.data) soft += v == 1, bone += v >= 2;
  const double voxel_mm3 = labels.voxel_volume() * 1e9;
  auto tets = [](double volume_mm3, double size_mm) { return volume_mm3 / (0.1 * size_mm * size_mm * size_mm); };
  return tets(static_cast<double>(soft) * voxel_mm3, p.cell_size_mm) + tets(static_cast<double>(bone) * voxel_mm3, p.bone_cell_size_mm);
}

TetMesh mesh_label_volume(const Volume<std::uint8_t>& labels, const LabelTable& table, const ImageMeshParams& p) {
  check(p.facet_angle_deg > 0 && p.facet_angle_deg <= 30, "facet_angle", "an angle in (0, 30] degrees", p.facet_angle_deg);
  check(p.facet_size_mm > 0, "facet_size", "a size > 0 mm", p.facet_size_mm);
  check(p.facet_distance_mm > 0, "facet_distance", "a distance > 0 mm", p.facet_distance_mm);
  check(p.cell_radius_edge >= 2, "cell_radius_edge", "a ratio >= 2", p.cell_radius_edge);
  check(p.cell_size_mm > 0, "cell_size", "a size > 0 mm", p.cell_size_mm);
  check(p.bone_cell_size_mm > 0, "bone_cell_size", "a size > 0 mm", p.bone_cell_size_mm);
  check(p.bone_facet_size_mm > 0, "bone_facet_size", "a size > 0 mm", p.bone_facet_size_mm);
  validate_volume_geometry(labels.dims, labels.spacing, labels.origin, 1, "labels", "/labels");
  std::size_t tissue = 0, nonzero = 0;
  for (auto v : labels.data) tissue += v == 1, nonzero += v != 0;
  if (nonzero == 0) throw InputError("labels", "/labels", "a label volume with tissue (labels >= 1)", "only background");
  if (tissue == 0) throw InputError("labels", "/labels", "soft tissue (label 1) around the bones", "no soft-tissue voxel");
  {  // CGAL's initial sampling never ends on a body one voxel thick: at least 3 voxels along every axis.
    std::array<int, 3> lo{labels.dims}, hi{-1, -1, -1};
    for (int k = 0; k < labels.dims[2]; ++k)
      for (int j = 0; j < labels.dims[1]; ++j)
        for (int i = 0; i < labels.dims[0]; ++i)
          if (labels.at(i, j, k)) {
            const int x[3] = {i, j, k};
            for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], x[a]), hi[a] = std::max(hi[a], x[a]);
          }
    for (int a = 0; a < 3; ++a)
      if (hi[a] - lo[a] + 1 < 3)
        throw InputError("labels", "/labels", "a labelled body at least 3 voxels thick along every axis (a volume to mesh)",
                         std::to_string(hi[a] - lo[a] + 1) + " voxel(s) along " + std::string(1, "xyz"[a]));
  }
  check(p.max_elements > 0, "max_elements", "a count > 0", p.max_elements);
  if (const double n = expected_tets(labels, p); n > p.max_elements) {
    std::ostringstream f;
    f << "about " << n << " tets at cell size " << p.cell_size_mm << " mm (bone " << p.bone_cell_size_mm << " mm)";
    throw InputError("labels", "cell size", "a mesh of at most " + std::to_string(static_cast<long long>(p.max_elements)) +
                                                " tets (coarser --cell-size / --bone-cell-size, or raise --max-elements)",
                     f.str());
  }

  // The image in millimetres (CGAL's criteria are absolute lengths); nodes go back to metres.
  _image* im = _createImage(static_cast<std::size_t>(labels.dims[0]), static_cast<std::size_t>(labels.dims[1]),
                            static_cast<std::size_t>(labels.dims[2]), 1, labels.spacing[0] * 1e3, labels.spacing[1] * 1e3,
                            labels.spacing[2] * 1e3, 1, WK_FIXED, SGN_UNSIGNED);
  std::memcpy(im->data, labels.data.data(), labels.size());
  CGAL::Image_3 image(im);
  CGAL::get_default_random() = CGAL::Random(p.seed);
  Domain domain = Domain::create_labeled_image_mesh_domain(image, CGAL::parameters::relative_error_bound = 1e-6,
                                                           CGAL::parameters::value_outside = 0);
  // Finer cells in bone, and finer facets on the bone surfaces: facets are chords of the
  // boundary, so a convex bone meshed with the skin's facet size loses ~13 % of its volume.
  SizeField size(p.cell_size_mm), facet_size(p.facet_size_mm);
  for (const auto& [id, name] : table)
    if (id >= 2) {
      size.set_size(p.bone_cell_size_mm, 3, domain.index_from_subdomain_index(id));
      facet_size.set_size(p.bone_facet_size_mm, 2, domain.index_from_surface_patch_index(Domain::Surface_patch_index(1, id)));
    }
  Criteria criteria(CGAL::parameters::facet_angle = p.facet_angle_deg, CGAL::parameters::facet_size = facet_size,
                    CGAL::parameters::facet_distance = p.facet_distance_mm,
                    CGAL::parameters::cell_radius_edge_ratio = p.cell_radius_edge, CGAL::parameters::cell_size = size);
  const double limit = p.optimiser_time_limit_s;
  auto optimise = [&](C3t3& c3t3) {
    CGAL::refine_mesh_3(
        c3t3, domain, criteria,
        p.odt ? CGAL::parameters::odt(CGAL::parameters::time_limit = limit) : CGAL::parameters::no_odt(),
        p.lloyd ? CGAL::parameters::lloyd(CGAL::parameters::time_limit = limit) : CGAL::parameters::no_lloyd(),
        p.perturb ? CGAL::parameters::perturb(CGAL::parameters::time_limit = limit, CGAL::parameters::sliver_bound = p.exude_sliver_bound_deg)
                  : CGAL::parameters::no_perturb(),
        p.exude ? CGAL::parameters::exude(CGAL::parameters::time_limit = limit, CGAL::parameters::sliver_bound = p.exude_sliver_bound_deg)
                : CGAL::parameters::no_exude());
  };
  std::set<int> wanted;
  for (auto v : labels.data)
    if (v) wanted.insert(v);
  auto missing_labels = [&](const C3t3& c) {
    std::set<int> seen, missing;
    for (auto cell = c.cells_in_complex_begin(); cell != c.cells_in_complex_end(); ++cell) seen.insert(static_cast<int>(c.subdomain_index(cell)));
    for (int l : wanted)
      if (!seen.count(l)) missing.insert(l);
    return missing;
  };
  // Default initialisation (random surface sampling) gives the better elements.
  C3t3 c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria, CGAL::parameters::no_odt(), CGAL::parameters::no_lloyd(),
                                      CGAL::parameters::no_perturb(), CGAL::parameters::no_exude());
  std::set<int> missing = missing_labels(c3t3);
  for (int attempt = 0; attempt < 4 && !missing_labels(c3t3).empty(); ++attempt) {
    for (int l : missing_labels(c3t3)) missing.insert(l);
    // A small subdomain was missed: the same random sampling plus a few surface points on each
    // missed label only (seeding every component of every label, as CGAL's
    // initialize_triangulation_from_labeled_image does, clusters tiny tets along all surfaces).
    std::string names;
    for (int l : missing) names += (names.empty() ? "" : ", ") + (table.count(l) ? table.at(l) : std::to_string(l));
    log::verbose() << "mesher: the initial sampling missed " << names << "; adding surface points on them";
    c3t3 = C3t3();
    CGAL::get_default_random() = CGAL::Random(p.seed);
    std::vector<std::pair<Domain::Point_3, Domain::Index>> points;
    domain.construct_initial_points_object()(std::back_inserter(points));
    const double sp[3] = {labels.spacing[0] * 1e3, labels.spacing[1] * 1e3, labels.spacing[2] * 1e3};
    auto label_at = [&](const double q[3]) {
      long idx[3];
      for (int a = 0; a < 3; ++a) {
        idx[a] = std::lround(q[a] / sp[a]);
        if (idx[a] < 0 || idx[a] >= labels.dims[a]) return -1;
      }
      return static_cast<int>(labels.at(static_cast<int>(idx[0]), static_cast<int>(idx[1]), static_cast<int>(idx[2])));
    };
    for (int l : missing) {
      double sum[3] = {0, 0, 0};
      std::size_t n = 0;
      for (int k = 0; k < labels.dims[2]; ++k)
        for (int j = 0; j < labels.dims[1]; ++j)
          for (int i = 0; i < labels.dims[0]; ++i)
            if (labels.at(i, j, k) == l) sum[0] += static_cast<double>(i), sum[1] += static_cast<double>(j), sum[2] += static_cast<double>(k), ++n;
      double c[3] = {0, 0, 0}, best = 1e300;  // the label's voxel nearest to its centroid
      for (int k = 0; k < labels.dims[2]; ++k)
        for (int j = 0; j < labels.dims[1]; ++j)
          for (int i = 0; i < labels.dims[0]; ++i)
            if (labels.at(i, j, k) == l) {
              const double d = std::pow(static_cast<double>(i) - sum[0] / static_cast<double>(n), 2) +
                               std::pow(static_cast<double>(j) - sum[1] / static_cast<double>(n), 2) +
                               std::pow(static_cast<double>(k) - sum[2] / static_cast<double>(n), 2);
              if (d < best) best = d, c[0] = static_cast<double>(i) * sp[0], c[1] = static_cast<double>(j) * sp[1], c[2] = static_cast<double>(k) * sp[2];
            }
      // Rays along the axes and the diagonals, each cut at its first voxel outside the label.
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            if (dx == 0 && dy == 0 && dz == 0) continue;
            const double len = std::sqrt(static_cast<double>(dx * dx + dy * dy + dz * dz));
            const double d[3] = {dx / len, dy / len, dz / len};
            const double step = 0.5 * std::min({sp[0], sp[1], sp[2]});
            double q[3] = {c[0], c[1], c[2]};
            int steps = 0;
            while (label_at(q) == l && steps < 10000) {
              for (int a = 0; a < 3; ++a) q[a] += step * d[a];
              ++steps;
            }
            for (int a = 0; a < 3; ++a) q[a] += 2 * step * d[a];
            const auto hit = domain.construct_intersection_object()(Domain::Segment_3(Domain::Point_3(c[0], c[1], c[2]), Domain::Point_3(q[0], q[1], q[2])));
            if (std::get<2>(hit) == 2) points.emplace_back(std::get<0>(hit), std::get<1>(hit));
            log::debug() << "mesher: label " << l << " ray from (" << c[0] << ", " << c[1] << ", " << c[2] << ") mm, " << steps
                         << " steps inside, hit dimension " << std::get<2>(hit);
          }
    }
    auto cwp = c3t3.triangulation().geom_traits().construct_weighted_point_3_object();
    for (const auto& [point, idx] : points) {
      const auto v = c3t3.triangulation().insert(cwp(point));
      if (v != Tr::Vertex_handle()) c3t3.set_dimension(v, 2), c3t3.set_index(v, idx);
    }
    CGAL::refine_mesh_3(c3t3, domain, criteria, CGAL::parameters::no_odt(), CGAL::parameters::no_lloyd(),
                        CGAL::parameters::no_perturb(), CGAL::parameters::no_exude());
  }
  {
    if (const std::set<int> still = missing_labels(c3t3); !still.empty()) {
      std::string names_left;
      for (int l : still) names_left += (names_left.empty() ? "" : ", ") + (table.count(l) ? table.at(l) : std::to_string(l));
      log::verbose() << "mesher: still missing " << names_left << "; seeding every component of every label";
      c3t3 = C3t3();
      {
        // CGAL 5.5 prints its progress to std::cout here; keep our stdout for our own output.
        std::ostringstream sink;
        std::streambuf* saved = std::cout.rdbuf(sink.rdbuf());
        ::initialize_triangulation_from_labeled_image(c3t3, domain, image, criteria, static_cast<unsigned char>(0));
        std::cout.rdbuf(saved);
      }
      CGAL::refine_mesh_3(c3t3, domain, criteria, CGAL::parameters::no_odt(), CGAL::parameters::no_lloyd(),
                          CGAL::parameters::no_perturb(), CGAL::parameters::no_exude());
    }
  }
  optimise(c3t3);

  TetMesh mesh;
  std::map<Tr::Vertex_handle, int> index;
  const Vec3 origin = labels.origin;
  auto node = [&](Tr::Vertex_handle v) {
    auto [it, fresh] = index.emplace(v, static_cast<int>(mesh.nodes.size()));
    if (fresh) {
      const auto& q = v->point().point();
      mesh.nodes.push_back({origin[0] + q.x() * 1e-3, origin[1] + q.y() * 1e-3, origin[2] + q.z() * 1e-3});
    }
    return it->second;
  };
  std::map<int, std::size_t> per_label;
  std::vector<int> triangle_inner;
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
    std::array<int, 4> t = {node(c->vertex(0)), node(c->vertex(1)), node(c->vertex(2)), node(c->vertex(3))};
    if (tet_volume(mesh.nodes[static_cast<std::size_t>(t[0])], mesh.nodes[static_cast<std::size_t>(t[1])],
                   mesh.nodes[static_cast<std::size_t>(t[2])], mesh.nodes[static_cast<std::size_t>(t[3])]) < 0)
      std::swap(t[2], t[3]);
    mesh.tets.push_back(t);
    const int label = static_cast<int>(c3t3.subdomain_index(c));
    mesh.tet_group.push_back(label);
    ++per_label[label];
  }
  for (auto f = c3t3.facets_in_complex_begin(); f != c3t3.facets_in_complex_end(); ++f) {
    const auto [a, b] = c3t3.surface_patch_index(*f);
    const int lo = std::min(a, b), hi = std::max(a, b);
    if (lo == hi) continue;
    // Orient outward from the inner material: soft tissue for the skin, bone for interfaces.
    Tr::Cell_handle cell = f->first;
    int i = f->second;
    const int inner = hi;  // soft tissue under the skin (0 | 1), the bone at an interface (1 | b)
    if (!c3t3.is_in_complex(cell) || static_cast<int>(c3t3.subdomain_index(cell)) != inner) {
      const auto mirror = c3t3.triangulation().mirror_facet(*f);
      cell = mirror.first, i = mirror.second;
    }
    std::array<int, 3> tri{};
    int k = 0;
    for (int j = 0; j < 4; ++j)
      if (j != i) tri[static_cast<std::size_t>(k++)] = node(cell->vertex(j));
    const Vec3 apex = mesh.nodes[static_cast<std::size_t>(node(cell->vertex(i)))];
    if (tet_volume(mesh.nodes[static_cast<std::size_t>(tri[0])], mesh.nodes[static_cast<std::size_t>(tri[1])],
                   mesh.nodes[static_cast<std::size_t>(tri[2])], apex) > 0)
      std::swap(tri[1], tri[2]);
    mesh.triangles.push_back(tri);
    mesh.triangle_group.push_back(lo == 0 ? kSkinTag : kBoneInterfaceTag);
    triangle_inner.push_back(lo == 0 ? 0 : inner);  // 0: the outer skin
  }
  if (p.restore_volumes) restore_volumes(mesh, labels, triangle_inner);
  if (p.relocate_passes > 0) relocate_short_tets(mesh, 0.35, p.facet_distance_mm * 1e-3, p.relocate_passes);
  if (p.peel_skin_slivers) {
    // Sweeps until nothing changes: peeling one sliver can put its neighbour flat on the skin.
    std::size_t peeled = 0;
    for (int sweep = 0; sweep < 8; ++sweep) {
      const std::size_t n = peel_skin_slivers(mesh, 0.3);
      peeled += n;
      if (n == 0) break;
    }
    log::verbose() << "mesher: peeled " << peeled << " soft-tissue slivers lying on the skin";
    if (peeled > 0 && p.relocate_passes > 0) relocate_short_tets(mesh, 0.35, p.facet_distance_mm * 1e-3, p.relocate_passes);
  }
  {
    std::map<int, std::size_t> voxels;
    for (auto v : labels.data)
      if (v) ++voxels[v];
    for (const auto& [label, n] : voxels)
      if (!per_label.count(label)) {
        auto it = table.find(label);
        throw NumericalError("mesher: label " + std::to_string(label) + " (" + (it != table.end() ? it->second : "?") + ", " +
                             std::to_string(n) + " voxels) received no tetrahedra; refine --bone-cell-size/--bone-facet-size");
      }
  }
  for (const auto& [label, count] : per_label) {
    auto it = table.find(label);
    mesh.groups.push_back({3, label, it != table.end() ? it->second : "label_" + std::to_string(label)});
  }
  mesh.groups.push_back({2, kSkinTag, "skin"});
  mesh.groups.push_back({2, kBoneInterfaceTag, "bone_interface"});
  log::verbose() << "mesher: " << mesh.nodes.size() << " nodes, " << mesh.tets.size() << " tets, " << mesh.triangles.size()
                 << " boundary triangles";
  return mesh;
}

}  // namespace tactus::mesher
