// Rigid bodies (rigid.hpp): finding them, their mass properties, the free rotation.
#include "tactus/solver/rigid.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

#include "tactus/core/error.hpp"
#include "tactus/core/state_file.hpp"

namespace tactus::solver {

namespace {

std::int32_t find_root(std::vector<std::int32_t>& parent, std::int32_t a) {
  while (parent[static_cast<std::size_t>(a)] != a)
    a = parent[static_cast<std::size_t>(a)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(a)])];
  return a;
}

// The rotation by angle t about axis e_i.
Mat3 axis_rotation(int i, double t) {
  const double c = std::cos(t), s = std::sin(t);
  Mat3 r = Mat3::Identity();
  const int j = (i + 1) % 3, k = (i + 2) % 3;
  r(j, j) = c, r(j, k) = -s, r(k, j) = s, r(k, k) = c;
  return r;
}

}  // namespace

Vec3d RigidBody::rotation_vector() const {
  const Eigen::AngleAxisd turn(rotation);
  return turn.angle() * turn.axis();
}

Mat3 RigidBody::inverse_inertia() const {
  // I(t)^-1 = R A diag(1/I) A^T R^T (A the principal axes).
  const Mat3 frame = rotation * axes;
  return frame * principal.cwiseInverse().asDiagonal() * frame.transpose();
}

std::vector<char> rigid_nodes(const Model& m) {
  std::vector<char> rigid(m.num_nodes, 0);
  for (const MaterialBlock& b : m.blocks)
    if (b.material.rigid())
      for (std::size_t e = b.begin; e < b.end; ++e)
        for (int k = 0; k < 4; ++k) rigid[static_cast<std::size_t>(m.conn[4 * e + k])] = 1;
  return rigid;
}

std::vector<RigidBody> find_rigid_bodies(const Model& m) {
  std::vector<RigidBody> out;
  std::vector<std::int32_t> parent(m.num_nodes);
  std::iota(parent.begin(), parent.end(), 0);
  const std::vector<char> rigid_node = rigid_nodes(m);
  std::vector<double> rigid_share(m.num_nodes, 0.0);  // the rigid tets' part of each node's lumped mass
  bool any = false;
  for (const MaterialBlock& b : m.blocks) {
    if (!b.material.rigid()) continue;
    any = true;
    for (std::size_t e = b.begin; e < b.end; ++e) {
      const std::int32_t* c = &m.conn[4 * e];
      for (int k = 0; k < 4; ++k) {
        rigid_share[static_cast<std::size_t>(c[k])] += 0.25 * b.material.density() * m.volume[e];
        const std::int32_t a = find_root(parent, c[0]), r = find_root(parent, c[k]);
        if (a != r) parent[static_cast<std::size_t>(std::max(a, r))] = std::min(a, r);
      }
    }
  }
  if (!any) return out;
  // One body per connected piece, numbered by its smallest node; named by its body and material.
  std::map<std::int32_t, std::size_t> index;
  for (const MaterialBlock& b : m.blocks) {
    if (!b.material.rigid()) continue;
    for (std::size_t e = b.begin; e < b.end; ++e) {
      const std::int32_t root = find_root(parent, m.conn[4 * e]);
      auto [it, added] = index.emplace(root, out.size());
      if (added) {
        RigidBody r;
        r.body = static_cast<std::size_t>(m.tet_body[static_cast<std::size_t>(m.input_element[e])]);
        r.name = m.bodies[r.body].name + "/" + b.name;
        out.push_back(std::move(r));
      }
      // Mass and second moment of the tet about the origin, exactly: int x x^T dV = V/20 (sum_i x_i x_i^T + s s^T).
      RigidBody& r = out[it->second];
      const double rho = b.material.density(), V = m.volume[e];
      Vec3d s = Vec3d::Zero();
      Mat3 xx = Mat3::Zero();
      for (int k = 0; k < 4; ++k) {
        const Vec3d x(&m.X[3 * static_cast<std::size_t>(m.conn[4 * e + k])]);
        s += x, xx += x * x.transpose();
      }
      r.mass += rho * V;
      r.centre0 += rho * V * 0.25 * s;                          // (first moment; divided by the mass below)
      r.inertia0 += rho * V / 20.0 * (xx + s * s.transpose());  // (second moment, turned into the inertia below)
    }
  }
  for (std::size_t a = 0; a < m.num_nodes; ++a)  // each body's nodes, ascending, in one pass
    if (rigid_node[a]) out[index.at(find_root(parent, static_cast<std::int32_t>(a)))].nodes.push_back(static_cast<std::int32_t>(a));
  std::map<std::string, int> pieces;
  for (const auto& [root, k] : index) {
    RigidBody& r = out[k];
    // The deformable tets' lumped mass on the shared nodes moves with the body: point masses.
    for (std::int32_t a : r.nodes) {
      const double extra = m.mass[static_cast<std::size_t>(a)] - rigid_share[static_cast<std::size_t>(a)];
      if (!(extra > 0)) continue;
      const Vec3d x(&m.X[3 * static_cast<std::size_t>(a)]);
      r.mass += extra, r.centre0 += extra * x, r.inertia0 += extra * x * x.transpose();
    }
    r.centre0 /= r.mass;
    const Mat3 C = r.inertia0 - r.mass * r.centre0 * r.centre0.transpose();  // second moment about the centre
    r.inertia0 = C.trace() * Mat3::Identity() - C;
    Eigen::SelfAdjointEigenSolver<Mat3> eig(r.inertia0);
    r.axes = eig.eigenvectors();
    if (r.axes.determinant() < 0) r.axes.col(2) *= -1.0;
    r.principal = eig.eigenvalues();
    r.name += " #" + std::to_string(++pieces[r.name]);
    for (std::int32_t a : r.nodes)
      for (int d = 0; d < 3; ++d) r.offset.push_back(m.X[3 * static_cast<std::size_t>(a) + static_cast<std::size_t>(d)] - r.centre0[d]);
    r.centre = r.centre0;
    const BodyRange& body = m.bodies[r.body];
    r.prescribed = body.rigid_prescribed;
    r.velocity = Vec3d(body.rigid_velocity.data()), r.angular_velocity = Vec3d(body.rigid_angular_velocity.data());
    r.curve = body.rigid_curve;
    for (std::int32_t a : r.nodes)
      for (int d = 0; d < 3; ++d)
        if (m.constrained[3 * static_cast<std::size_t>(a) + static_cast<std::size_t>(d)])
          throw InputError("scenario", "boundary", "no [[boundary]] on the nodes of a rigid body (give bodies.rigid_velocity instead)",
                           "one on " + r.name);
    if (!(r.principal.minCoeff() > 0))
      throw InputError("scenario", "materials", "rigid pieces with a volume", r.name + " has no rotational inertia (a flat or degenerate piece)");
  }
  return out;
}

Mat3 free_rotation(const RigidBody& b, const Mat3& rotation, const Vec3d& L, double dt) {
  // In the principal frame R = Q A the body-frame angular momentum is pi = R^T L; the flow of
  // pi_i^2 / (2 I_i) alone turns the body about its axis i by dt pi_i / I_i (pi turning back, L
  // unchanged). Strang splitting x(dt/2) y(dt/2) z(dt) y(dt/2) x(dt/2).
  Mat3 R = rotation * b.axes;
  Vec3d pi = R.transpose() * L;
  auto sub = [&](int i, double h) {
    const Mat3 turn = axis_rotation(i, h * pi[i] / b.principal[i]);
    R = R * turn;
    pi = turn.transpose() * pi;
  };
  sub(0, 0.5 * dt), sub(1, 0.5 * dt), sub(2, dt), sub(1, 0.5 * dt), sub(0, 0.5 * dt);
  return R * b.axes.transpose();
}

void rigid_displacements(const RigidBody& b, const Model& m, const Vec3d& centre, const Mat3& rotation, double* u) {
  for (std::size_t k = 0; k < b.nodes.size(); ++k) {
    const auto a = static_cast<std::size_t>(b.nodes[k]);
    const Vec3d x = centre + rotation * Vec3d(&b.offset[3 * k]);
    for (int d = 0; d < 3; ++d) u[3 * a + static_cast<std::size_t>(d)] = x[d] - m.X[3 * a + static_cast<std::size_t>(d)];
  }
}

void checkpoint_rigid_bodies(StateArchive& a, std::vector<RigidBody>& bodies) {
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    RigidBody& r = bodies[k];
    const std::string p = "rigid" + std::to_string(k) + ".";
    for (auto [name, v] : {std::pair<const char*, Vec3d*>{"centre", &r.centre},
                           {"momentum", &r.momentum},
                           {"angular_momentum", &r.angular_momentum},
                           {"momentum_before", &r.momentum_before},
                           {"angular_momentum_before", &r.angular_momentum_before},
                           {"force", &r.force},
                           {"moment", &r.moment},
                           {"reaction_force", &r.reaction_force},
                           {"reaction_moment", &r.reaction_moment}}) {
      std::vector<double> x(v->data(), v->data() + 3);
      a.io(p + name, x, 3);
      *v = Vec3d(x.data());
    }
    std::vector<double> q(r.rotation.data(), r.rotation.data() + 9);
    a.io(p + "rotation", q, 9);
    r.rotation = Eigen::Map<const Mat3>(q.data());
  }
}

}  // namespace tactus::solver
