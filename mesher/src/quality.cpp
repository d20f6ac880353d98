#include "tactus/mesher/quality.hpp"
#include "tactus/mesher/well_composed.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "tactus/core/stable_step.hpp"

namespace tactus::mesher {

namespace {
std::array<double, 3> sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
std::array<double, 3> cross(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const std::array<double, 3>& a, const std::array<double, 3>& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const std::array<double, 3>& a) { return std::sqrt(dot(a, a)); }
}  // namespace

TetQuality tet_quality(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Vec3 p[4] = {a, b, c, d};
  TetQuality q{};
  q.volume = tet_volume(a, b, c, d);
  q.length = characteristic_length(a, b, c, d);
  // Dihedral angle at edge (i,j): between the faces (i,j,k) and (i,j,l).
  const int edges[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2}, {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};
  q.min_dihedral_deg = 180, q.max_dihedral_deg = 0;
  double emin = 1e300, emax = 0;
  for (const auto& e : edges) {
    const auto axis = sub(p[e[1]], p[e[0]]);
    const auto n1 = cross(axis, sub(p[e[2]], p[e[0]])), n2 = cross(axis, sub(p[e[3]], p[e[0]]));
    const double c0 = dot(n1, n2) / (norm(n1) * norm(n2));
    const double angle = std::acos(std::clamp(c0, -1.0, 1.0)) * 180.0 / M_PI;
    q.min_dihedral_deg = std::min(q.min_dihedral_deg, angle);
    q.max_dihedral_deg = std::max(q.max_dihedral_deg, angle);
    emin = std::min(emin, norm(axis)), emax = std::max(emax, norm(axis));
  }
  q.edge_ratio = emax / emin;
  // Radius ratio 3 r_in / R_circ (1 for the regular tet, 0 for a flat one).
  double area = 0;
  for (int f = 0; f < 4; ++f) area += 0.5 * norm(cross(sub(p[(f + 2) % 4], p[(f + 1) % 4]), sub(p[(f + 3) % 4], p[(f + 1) % 4])));
  const double r_in = 3.0 * std::abs(q.volume) / area;
  const auto u = sub(b, a), v = sub(c, a), w = sub(d, a);
  const auto num = [&] {
    const auto vw = cross(v, w), wu = cross(w, u), uv = cross(u, v);
    const double uu = dot(u, u), vv = dot(v, v), ww = dot(w, w);
    return std::array<double, 3>{uu * vw[0] + vv * wu[0] + ww * uv[0], uu * vw[1] + vv * wu[1] + ww * uv[1], uu * vw[2] + vv * wu[2] + ww * uv[2]};
  }();
  const double R = norm(num) / (12.0 * std::abs(q.volume));
  q.radius_ratio = 3.0 * r_in / R;
  return q;
}

QualityAdvice QualityAdvice::gmsh_object() {
  QualityAdvice a;
  a.surface_angle =
      "its four nodes lie on the object's surface, which gmsh meshes first and keeps: a surface detail or a change of size finer than "
      "--element-size (a smaller --element-size resolves it; for a box, an --edge-radius of at least about the element size)";
  a.interior_angle = "gmsh's optimisation could not raise it (a smaller --element-size usually does)";
  a.short_length =
      "a tet much smaller or flatter than a typical one, where the sizes grade or the surface has fine detail (a smaller "
      "--element-size evens the sizes), or accept the stable step it sets";
  return a;
}

namespace {

// One subdomain's (or the whole mesh's) quality figures, accumulated tet by tet.
struct Acc {
  std::size_t tets = 0, slivers = 0, below10 = 0, inverted = 0, below_goal_angle = 0;
  std::size_t worst_angle_tet = 0, shortest_tet = 0;
  double volume = 0, min_dihedral = 180, max_dihedral = 0, min_radius_ratio = 1, max_edge_ratio = 0, min_length = 1e300;
  std::vector<std::pair<double, double>> lengths;  // (L_e, volume) of each tet: the volumes weigh the added mass
  std::array<std::size_t, 18> dihedral_hist{};     // 10-degree bins of the minimum dihedral angle
  void add(const TetQuality& q, std::size_t e, double sliver_deg, const QualityGuarantees& goal) {
    ++tets;
    volume += q.volume;
    inverted += q.volume <= 0;
    slivers += q.min_dihedral_deg < sliver_deg;
    below10 += q.min_dihedral_deg < 10;
    below_goal_angle += q.min_dihedral_deg < goal.min_dihedral_deg;
    if (q.min_dihedral_deg < min_dihedral) worst_angle_tet = e;
    if (q.length < min_length) min_length = q.length, shortest_tet = e;
    min_dihedral = std::min(min_dihedral, q.min_dihedral_deg);
    max_dihedral = std::max(max_dihedral, q.max_dihedral_deg);
    min_radius_ratio = std::min(min_radius_ratio, q.radius_ratio);
    max_edge_ratio = std::max(max_edge_ratio, q.edge_ratio);
    lengths.emplace_back(q.length, q.volume);
    ++dihedral_hist[static_cast<std::size_t>(std::clamp(q.min_dihedral_deg / 10.0, 0.0, 17.0))];
  }
  double median_length() const { return lengths.empty() ? 0 : lengths[lengths.size() / 2].first; }  // once sorted
  // The figures as quality.json holds them (sorts the lengths for their median).
  nlohmann::json to_json(double step_ratio);
  // The mass, as a fraction of the subdomain's, that mass scaling adds to bring every tet's step
  // L_e / c up to `ratio` of the median tet's: a tet's mass scales by (ratio L_median / L_e)^2,
  // since its step grows as the square root of its mass. One density and one wave speed per
  // subdomain, so volumes stand for masses and lengths for steps. Valid after to_json.
  double added_mass_fraction(double ratio) const {
    if (lengths.empty() || volume <= 0) return 0;
    const double target = ratio * median_length();
    double added = 0;
    for (const auto& [length, v] : lengths) {
      if (length >= target) break;
      added += v * ((target / length) * (target / length) - 1);
    }
    return added / volume;
  }
};

nlohmann::json Acc::to_json(double step_ratio) {
  std::sort(lengths.begin(), lengths.end());
  const double median = median_length();
  const double smallest = lengths.empty() ? 0 : lengths.front().first;
  return nlohmann::json{{"tets", tets},
                        {"volume_m3", volume},
                        {"inverted", inverted},
                        {"min_dihedral_deg", min_dihedral},
                        {"max_dihedral_deg", max_dihedral},
                        {"fraction_min_dihedral_below_10deg", tets ? static_cast<double>(below10) / static_cast<double>(tets) : 0},
                        {"slivers", slivers},
                        {"min_radius_ratio", min_radius_ratio},
                        {"max_edge_ratio", max_edge_ratio},
                        {"min_length_m", smallest},
                        {"median_length_m", median},
                        {"min_over_median_length", median > 0 ? smallest / median : 0},
                        {"added_mass_fraction_for_step_ratio", added_mass_fraction(step_ratio)},
                        {"min_dihedral_histogram_10deg_bins", dihedral_hist}};
}

// Each guarantee a subdomain misses, with its worst tet, where it is, and why.
void add_unmet(const TetMesh& mesh, const std::string& name, const Acc& a, const std::vector<char>& on_surface, const QualityGuarantees& goal,
               const QualityAdvice& advice, nlohmann::json& unmet) {
  const auto centroid = [&](std::size_t e) {
    std::array<double, 3> c{0, 0, 0};
    for (int v : mesh.tets[e])
      for (std::size_t i = 0; i < 3; ++i) c[i] += 0.25 * mesh.nodes[static_cast<std::size_t>(v)][i];
    return c;
  };
  if (a.min_dihedral < goal.min_dihedral_deg) {
    int surface = 0;
    for (int v : mesh.tets[a.worst_angle_tet]) surface += on_surface[static_cast<std::size_t>(v)];
    unmet.push_back({{"group", name},
                     {"guarantee", "min_dihedral_deg"},
                     {"value", a.min_dihedral},
                     {"tets_below", a.below_goal_angle},
                     {"element", a.worst_angle_tet + 1},
                     {"at_m", centroid(a.worst_angle_tet)},
                     {"nodes_on_surfaces", surface},
                     {"why", surface == 4 ? advice.surface_angle : advice.interior_angle}});
  }
  const double median = a.median_length();
  const double added_mass = a.added_mass_fraction(goal.min_length_ratio);
  if (a.min_length < goal.min_length_ratio * median && added_mass > goal.max_added_mass_fraction) {
    const auto below = std::lower_bound(a.lengths.begin(), a.lengths.end(), goal.min_length_ratio * median,
                                        [](const std::pair<double, double>& t, double length) { return t.first < length; }) -
                       a.lengths.begin();
    std::ostringstream why;
    why << "L_e " << a.min_length * 1e3 << " mm against the subdomain's median " << median * 1e3 << " mm, and mass scaling to "
        << goal.min_length_ratio << " of the median tet's step would add " << 100 * added_mass << " % of its mass (at most "
        << 100 * goal.max_added_mass_fraction << " %): " << advice.short_length;
    unmet.push_back({{"group", name},
                     {"guarantee", "min_over_median_length"},
                     {"value", a.min_length / median},
                     {"added_mass_fraction", added_mass},
                     {"tets_below", below},
                     {"element", a.shortest_tet + 1},
                     {"at_m", centroid(a.shortest_tet)},
                     {"why", why.str()}});
  }
}

// The critical step of the mesh for the given wave speeds (none: 1000 m/s), or null.
nlohmann::json critical_step_report(const TetMesh& mesh, const std::map<int, double>& wave_speed) {
  nlohmann::json out;
  const CriticalStep step = critical_time_step(mesh, [&](int tag) {
    auto it = wave_speed.find(tag);
    return it == wave_speed.end() ? 0.0 : it->second;
  });
  if (step.element >= 0) {
    const auto* g = mesh.find_group(3, step.group);
    out = {{"dt_s", step.dt},
           {"element", step.element + 1},
           {"group", g ? g->name : ""},
           {"length_m", step.length},
           {"wave_speed_m_per_s", wave_speed.at(step.group)},
           {"note",
            "for the wave speeds given with --wave-speed (1000 m/s everywhere when none: the step "
            "then scales as 1000 / speed)"}};
  }
  return out;
}

}  // namespace

nlohmann::json quality_report(const TetMesh& mesh, const std::map<int, double>& wave_speed, double sliver_deg, const QualityGuarantees& goal,
                              const QualityAdvice& advice) {
  std::map<int, Acc> acc;
  Acc all;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    const auto& t = mesh.tets[e];
    const TetQuality q = tet_quality(mesh.nodes[static_cast<std::size_t>(t[0])], mesh.nodes[static_cast<std::size_t>(t[1])],
                                     mesh.nodes[static_cast<std::size_t>(t[2])], mesh.nodes[static_cast<std::size_t>(t[3])]);
    for (Acc* a : {&acc[mesh.tet_group[e]], &all}) a->add(q, e, sliver_deg, goal);
  }
  nlohmann::json j;
  j["units"] = "SI (m, m^3, s); angles in degrees; length = L_e = (sum_a |grad N_a|^2)^(-1/2)";
  j["nodes"] = mesh.nodes.size();
  j["sliver_bound_deg"] = sliver_deg;
  j["all"] = all.to_json(goal.min_length_ratio);
  j["groups"] = nlohmann::json::object();
  // Per subdomain, its figures and the guarantees: each unmet one with its worst tet, where it
  // is, and why.
  std::vector<char> on_surface(mesh.nodes.size(), 0);
  for (const auto& f : mesh.triangles)
    for (int v : f) on_surface[static_cast<std::size_t>(v)] = 1;
  nlohmann::json unmet = nlohmann::json::array();
  for (auto& [tag, a] : acc) {
    const auto* g = mesh.find_group(3, tag);
    const std::string name = g ? g->name : std::to_string(tag);
    j["groups"][name] = a.to_json(goal.min_length_ratio);  // sorts a.lengths
    add_unmet(mesh, name, a, on_surface, goal, advice, unmet);
  }
  // The boundaries' topology: the skin and each group's own boundary, a closed 2-manifold each (a
  // guarantee like the others: CGAL's manifold criterion, then the mesher's pinch pass).
  j["boundaries"] = nlohmann::json::object();
  nlohmann::json boundary_unmet = nlohmann::json::array();
  for (const auto& [name, t] : boundary_topology(mesh)) {
    j["boundaries"][name] = {{"faces", t.faces}, {"non_manifold_edges", t.non_manifold_edges}, {"non_manifold_vertices", t.non_manifold_vertices}};
    if (t.non_manifold_edges + t.non_manifold_vertices > 0)
      boundary_unmet.push_back({{"group", name},
                                {"guarantee", "boundary_manifold"},
                                {"value", t.non_manifold_edges + t.non_manifold_vertices},
                                {"at_m", t.first_defect},
                                {"why", "the boundary of '" + name + "' has " + std::to_string(t.non_manifold_edges) + " non-manifold edge(s) and " +
                                            std::to_string(t.non_manifold_vertices) +
                                            " non-manifold vertex(es): parts of it touch along an edge or at a point (a label that touches itself "
                                            "diagonally in the voxels, or a pinch thinner than the elements)"}});
  }
  j["guarantees"] = {{"min_dihedral_deg", goal.min_dihedral_deg},
                     {"min_over_median_length", goal.min_length_ratio},
                     {"max_added_mass_fraction", goal.max_added_mass_fraction},
                     {"scope",
                      "every subdomain (volume group); L_e over the subdomain's median L_e (its critical step over its median tet's), "
                      "or else the mass that mass scaling adds to reach that step ratio (added_mass_fraction_for_step_ratio); and "
                      "boundary_manifold"},
                     {"met", unmet.empty() && boundary_unmet.empty()},
                     {"unmet", unmet},
                     {"boundary_manifold",
                      {{"scope", "the skin and every group's own boundary a 2-manifold (each edge in two of its faces, each vertex's faces one fan)"},
                       {"met", boundary_unmet.empty()},
                       {"unmet", boundary_unmet}}}};
  if (nlohmann::json step = critical_step_report(mesh, wave_speed); !step.is_null()) j["critical_time_step"] = step;
  return j;
}

}  // namespace tactus::mesher
