// Rule-based fibre fields (fibres.hpp): a Poisson problem on the P1 tet mesh, solved by
// conjugate gradients on the free nodes, and the nearest skin triangle of every tet (a CGAL AABB
// tree), then per-tet directions.
#include "tactus/mesher/fibres.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>

#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/stable_step.hpp"
#include "tactus/core/vec3.hpp"

namespace tactus::mesher {

namespace {

using Sparse = Eigen::SparseMatrix<double>;

struct Operators {
  Sparse K;                         // P1 stiffness sum_e V_e grad N_a . grad N_b
  std::vector<double> lumped;       // nodal volumes sum_e V_e / 4 (the unit source's load)
  std::vector<TetGradients> grads;  // per tet
};

Operators assemble(const TetMesh& mesh) {
  Operators op;
  const std::size_t n = mesh.nodes.size();
  op.lumped.assign(n, 0.0);
  op.grads.resize(mesh.tets.size());
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(16 * mesh.tets.size());
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    const auto& t = mesh.tets[e];
    const TetGradients g = tet_shape_gradients(mesh.nodes[t[0]], mesh.nodes[t[1]], mesh.nodes[t[2]], mesh.nodes[t[3]]);
    op.grads[e] = g;
    const double V = std::abs(g.volume);
    for (int a = 0; a < 4; ++a) {
      op.lumped[static_cast<std::size_t>(t[a])] += 0.25 * V;
      for (int b = 0; b < 4; ++b) entries.emplace_back(t[a], t[b], V * dot(g.grad[a], g.grad[b]));
    }
  }
  op.K.resize(static_cast<int>(n), static_cast<int>(n));
  op.K.setFromTriplets(entries.begin(), entries.end());
  return op;
}

// -lap(u) = 1 with u = 0 on the `fixed` nodes: K_ff u_f = M_f 1, by preconditioned CG. Nodes of
// no tet (lumped volume 0) are left out, at 0.
std::vector<double> poisson(const Operators& op, const std::vector<char>& fixed) {
  const std::size_t n = fixed.size();
  std::vector<int> index(n, -1);
  int nf = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (!fixed[i] && op.lumped[i] > 0) index[i] = nf++;
  std::vector<Eigen::Triplet<double>> t;
  for (int c = 0; c < op.K.outerSize(); ++c)
    for (Sparse::InnerIterator it(op.K, c); it; ++it) {
      const int r = index[static_cast<std::size_t>(it.row())], cc = index[static_cast<std::size_t>(it.col())];
      if (r >= 0 && cc >= 0) t.emplace_back(r, cc, it.value());
    }
  Sparse Kf(nf, nf);
  Kf.setFromTriplets(t.begin(), t.end());
  Eigen::VectorXd f(nf);
  for (std::size_t i = 0; i < n; ++i)
    if (index[i] >= 0) f[index[i]] = op.lumped[i];
  Eigen::ConjugateGradient<Sparse, Eigen::Lower | Eigen::Upper, Eigen::IncompleteCholesky<double>> cg;
  cg.setTolerance(1e-10);
  cg.setMaxIterations(20000);
  cg.compute(Kf);
  const Eigen::VectorXd x = cg.solve(f);
  if (cg.info() != Eigen::Success)
    throw NumericalError("the fibre potentials did not converge (" + std::to_string(cg.iterations()) + " CG iterations, residual " +
                         std::to_string(cg.error()) + "): is every part of the mesh connected to the base and the skin?");
  std::vector<double> u(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    if (index[i] >= 0) u[i] = x[index[i]];
  return u;
}

Vec3 gradient(const TetGradients& g, const std::array<int, 4>& t, const std::vector<double>& u) {
  Vec3 out{0, 0, 0};
  for (int a = 0; a < 4; ++a)
    for (int d = 0; d < 3; ++d) out[d] += u[static_cast<std::size_t>(t[a])] * g.grad[a][d];
  return out;
}

// The unit normal of the skin triangle nearest to each point, and the distance to it (CGAL AABB tree).
void nearest_skin(const TetMesh& mesh, int skin_tag, const std::vector<Vec3>& points, std::vector<Vec3>& normal, std::vector<double>& distance) {
  using Kernel = CGAL::Simple_cartesian<double>;
  using Triangle = Kernel::Triangle_3;
  using Iterator = std::vector<Triangle>::const_iterator;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, CGAL::AABB_triangle_primitive<Kernel, Iterator>>>;
  std::vector<Triangle> triangles;
  std::vector<Vec3> normals;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (mesh.triangle_group[t] != skin_tag) continue;
    const auto& tri = mesh.triangles[t];
    const Vec3 &a = mesh.nodes[static_cast<std::size_t>(tri[0])], &b = mesh.nodes[static_cast<std::size_t>(tri[1])],
               &c = mesh.nodes[static_cast<std::size_t>(tri[2])];
    const Vec3 nrm = cross(b - a, c - a);
    if (!(norm(nrm) > 0)) continue;  // a degenerate triangle has no normal
    triangles.emplace_back(Kernel::Point_3(a[0], a[1], a[2]), Kernel::Point_3(b[0], b[1], b[2]), Kernel::Point_3(c[0], c[1], c[2]));
    normals.push_back((1 / norm(nrm)) * nrm);
  }
  Tree tree(triangles.cbegin(), triangles.cend());
  tree.accelerate_distance_queries();
  normal.resize(points.size()), distance.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Kernel::Point_3 q(points[i][0], points[i][1], points[i][2]);
    const auto [p, it] = tree.closest_point_and_primitive(q);
    normal[i] = normals[static_cast<std::size_t>(it - triangles.cbegin())];
    distance[i] = std::sqrt(CGAL::squared_distance(p, q));
  }
}

}  // namespace

FibreField rule_based_fibres(const TetMesh& mesh, const FibreFieldOptions& o, const std::string& source) {
  if (o.axis < 0 || o.axis > 2) throw InputError("command line", "--axis", "x, y or z", std::to_string(o.axis));
  if (!(o.base_fraction > 0 && o.base_fraction < 1))
    throw InputError("command line", "--base-fraction", "a fraction in (0, 1)", std::to_string(o.base_fraction));
  const PhysicalGroup* skin = mesh.find_group(2, o.skin_group);
  if (!skin) throw InputError(source, o.skin_group, "a physical surface group '" + o.skin_group + "' (the skin)", "none");
  const std::size_t n = mesh.nodes.size();
  FibreField out;
  std::vector<char> on_skin(n, 0), on_base(n, 0);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    if (mesh.triangle_group[t] == skin->tag)
      for (int v : mesh.triangles[t]) on_skin[static_cast<std::size_t>(v)] = 1;
  double lo = 1e300, hi = -1e300;
  for (const Vec3& x : mesh.nodes) lo = std::min(lo, x[o.axis]), hi = std::max(hi, x[o.axis]);
  for (std::size_t i = 0; i < n; ++i) on_base[i] = mesh.nodes[i][o.axis] <= lo + o.base_fraction * (hi - lo);
  out.skin_nodes = static_cast<std::size_t>(std::count(on_skin.begin(), on_skin.end(), 1));
  out.base_nodes = static_cast<std::size_t>(std::count(on_base.begin(), on_base.end(), 1));
  if (out.skin_nodes == 0) throw InputError(source, o.skin_group, "triangles in the skin group", "none");

  const Operators op = assemble(mesh);
  out.phi = poisson(op, on_base);

  const double c = std::cos(o.angle_deg * M_PI / 180), s = std::sin(o.angle_deg * M_PI / 180);
  Vec3 axis{0, 0, 0};
  axis[o.axis] = 1;
  const std::size_t E = mesh.tets.size();
  out.fibre_1.resize(E), out.fibre_2.resize(E), out.direction.resize(E), out.skin_normal.resize(E);
  // A gradient below 1e-6 of the largest in the mesh is taken as vanishing.
  double phi_scale = 0;
  std::vector<Vec3> gphi(E), centres(E);
  for (std::size_t e = 0; e < E; ++e) {
    gphi[e] = gradient(op.grads[e], mesh.tets[e], out.phi), phi_scale = std::max(phi_scale, norm(gphi[e]));
    centres[e] = {0, 0, 0};
    for (int v : mesh.tets[e])
      for (int d = 0; d < 3; ++d) centres[e][d] += 0.25 * mesh.nodes[static_cast<std::size_t>(v)][d];
  }
  nearest_skin(mesh, skin->tag, centres, out.skin_normal, out.skin_distance);
  for (std::size_t e = 0; e < E; ++e) {
    Vec3 l = norm(gphi[e]) > 1e-6 * phi_scale ? (1 / norm(gphi[e])) * gphi[e] : axis;
    const Vec3 nrm = out.skin_normal[e];
    // l in the plane of the nearest skin; where it is along n (a fingertip, the base), the axis, else any.
    for (const Vec3& candidate : {l, axis, Vec3{1, 0, 0}, Vec3{0, 1, 0}}) {
      const Vec3 in_plane = candidate - dot(candidate, nrm) * nrm;
      if (norm(in_plane) > 1e-3) {
        l = (1 / norm(in_plane)) * in_plane;
        break;
      }
    }
    // The circumferential direction: n x l, or any direction normal to l where n is undefined.
    Vec3 circ = cross(nrm, l);
    if (norm(circ) < 1e-3) circ = cross(std::abs(l[0]) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0}, l);
    circ = (1 / norm(circ)) * circ;
    out.direction[e] = l;
    for (int d = 0; d < 3; ++d) {
      out.fibre_1[e][d] = c * l[d] + s * circ[d];
      out.fibre_2[e][d] = c * l[d] - s * circ[d];
    }
  }
  log::info() << "fibres: " << E << " tets; base " << out.base_nodes << " nodes, skin " << out.skin_nodes << " nodes; families at +-" << o.angle_deg
              << " deg to the reference direction, in the plane parallel to the skin";
  return out;
}

}  // namespace tactus::mesher
