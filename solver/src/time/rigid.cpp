// Rigid bodies (rigid.hpp): finding them, their mass properties, the free rotation.
#include "tactus/solver/rigid.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

#include "../contact/bipotential.hpp"
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
        r.body = m.body_of_tet(static_cast<std::size_t>(m.input_element[e]));
        r.name = m.bodies[r.body].name + "/" + b.name;
        out.push_back(std::move(r));
      }
      // Mass and second moment of the tet about the origin, exactly: int x x^T dV = V/20 (sum_i x_i x_i^T + s s^T).
      RigidBody& r = out[it->second];
      const std::int32_t group = m.input_mesh.tet_group[static_cast<std::size_t>(m.input_element[e])];
      if (!std::binary_search(r.groups.begin(), r.groups.end(), group))
        r.groups.insert(std::upper_bound(r.groups.begin(), r.groups.end(), group), group);
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
    r.motion.velocity = Vec3d(body.rigid_velocity.data()), r.motion.angular_velocity = Vec3d(body.rigid_angular_velocity.data());
    r.motion.curve = body.rigid_curve;
    r.guide = Vec3d(body.rigid_guide.data());
    for (std::int32_t a : r.nodes)
      for (int d = 0; d < 3; ++d)
        if (m.constrained[3 * static_cast<std::size_t>(a) + static_cast<std::size_t>(d)])
          throw InputError(m.source, "boundary", "no [[boundary]] on the nodes of a rigid body (give bodies.rigid_velocity instead)",
                           "one on " + r.name);
    if (!(r.principal.minCoeff() > 0))
      throw InputError(m.source, "materials", "rigid pieces with a volume", r.name + " has no rotational inertia (a flat or degenerate piece)");
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

// ---------------------------------------------------------------------------------------------
RigidBodies::RigidBodies() = default;
RigidBodies::~RigidBodies() = default;
RigidBodies::RigidBodies(RigidBodies&&) noexcept = default;
RigidBodies& RigidBodies::operator=(RigidBodies&&) noexcept = default;

void RigidBodies::init(const Model& model, double* v_half, double* v_prev_half, double* contact_inv_mass) {
  bodies_ = find_rigid_bodies(model);
  if (bodies_.empty()) return;
  next_.resize(bodies_.size());
  rows_ = std::make_unique<RigidRows>();
  RigidRows& rows = *rows_;
  rows.X = model.X.data();
  piece_of_node_.assign(model.num_nodes, -1);
  rows.body_of_node = piece_of_node_.data();
  const std::size_t nb = bodies_.size();
  rows.centre.resize(nb), rows.V.resize(nb), rows.w.resize(nb), rows.inv_mass.resize(nb), rows.inv_inertia.resize(nb);
  rows.moved.resize(nb), rows.guide.resize(nb);
  for (RigidBody& b : bodies_) {
    const BodyRange& body = model.bodies[b.body];
    const auto a0 = static_cast<std::size_t>(b.nodes.front());
    Vec3d V, w;
    if (b.prescribed) {
      const double c = model.curve_at(b.motion.curve, 0.0);
      w = c * b.motion.angular_velocity;
      V = c * b.motion.velocity;
      if (b.motion.pivot) V += w.cross(b.centre0 - *b.motion.pivot);
    } else {  // the body's initial velocity field v0 + w x (X - c_body), at this piece's centre
      w = Vec3d(body.initial_angular_velocity.data());
      V = Vec3d(&model.initial_velocity[3 * a0]) + w.cross(b.centre0 - Vec3d(&model.X[3 * a0]));
      if (b.guided()) V = b.guide * b.guide.dot(V), w.setZero();  // on its rail from the start
    }
    for (int d = 0; d < 3; ++d) rows.guide[static_cast<std::size_t>(&b - bodies_.data())][static_cast<std::size_t>(d)] = b.guide[d];
    b.momentum_before = b.momentum = b.mass * V;
    b.angular_momentum_before = b.angular_momentum = b.inertia0 * w;
    for (std::size_t k = 0; k < b.nodes.size(); ++k) {
      const auto a = static_cast<std::size_t>(b.nodes[k]);
      piece_of_node_[a] = b.prescribed ? kPrescribed : static_cast<std::int32_t>(&b - bodies_.data());
      const Vec3d v = V + w.cross(Vec3d(&b.offset[3 * k]));
      for (std::size_t d = 0; d < 3; ++d) {
        v_half[3 * a + d] = v_prev_half[3 * a + d] = v[static_cast<Eigen::Index>(d)];
        contact_inv_mass[3 * a + d] = 0;  // held like a support in the contact sweep (its reaction moves the body)
      }
    }
  }
}

void RigidBodies::prescribe(std::size_t piece, const RigidMotion& motion) {
  if (piece >= bodies_.size())
    throw InputError("scenario", "rigid motion", "a rigid piece (" + std::to_string(bodies_.size()) + " in the model)",
                     "piece " + std::to_string(piece));
  RigidBody& b = bodies_[piece];
  b.motion = motion;
  if (b.prescribed) return;  // (a joint drive prescribes its bones every step)
  b.prescribed = true;
  for (std::int32_t a : b.nodes) piece_of_node_[static_cast<std::size_t>(a)] = kPrescribed;
}

void RigidBodies::sum_loads(const Model& model, const double* f, const ExternalForces& external, const double* u) {
  for (RigidBody& b : bodies_) {
    // Internal forces of the deformable tets on the shared nodes, gravity and follower pressures.
    Vec3d F = Vec3d::Zero(), T = Vec3d::Zero();
    for (std::int32_t node : b.nodes) {
      const auto a = static_cast<std::size_t>(node);
      Vec3d fa, r;
      for (std::size_t d = 0; d < 3; ++d) {
        fa[static_cast<Eigen::Index>(d)] = f[3 * a + d] + external.at(3 * a + d);
        r[static_cast<Eigen::Index>(d)] = model.X[3 * a + d] + u[3 * a + d] - b.centre[static_cast<Eigen::Index>(d)];
      }
      F += fa, T += r.cross(fa);
    }
    b.force = F, b.moment = T;
  }
}

void RigidBodies::kick(const Model& model, const double* u, double time, double t_next, double dt, double dtbar, double c_minus, double c_plus) {
  RigidRows& rows = *rows_;
  rows.u = u;
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    RigidBody& b = bodies_[k];
    const Vec3d F = b.force, T = b.moment;
    b.momentum_before = b.momentum, b.angular_momentum_before = b.angular_momentum;
    if (b.prescribed) {
      // The given motion over the step (its integral, as velocity boundaries do), and the support
      // force and moment that make it: what the kick would have to add.
      const RigidMotion& mo = b.motion;
      const double share = mo.curve < 0 ? dt
                                        : model.curves[static_cast<std::size_t>(mo.curve)].integral(t_next) -
                                              model.curves[static_cast<std::size_t>(mo.curve)].integral(time);
      if (!mo.pivot) {
        b.momentum = b.mass * mo.velocity * share / dt;
      } else {
        // About a pivot p carried with the piece: p moves by the velocity's integral and the
        // centre turns about it by the angle's, exactly (a joint's motion, as a chain prescribes it).
        const Vec3d angle = mo.angular_velocity * share;
        const Mat3 turn = angle.norm() > 0 ? Mat3(Eigen::AngleAxisd(angle.norm(), angle / angle.norm())) : Mat3::Identity();
        const Vec3d p = b.centre + b.rotation * (*mo.pivot - b.centre0);
        const Vec3d next_centre = p + mo.velocity * share + turn * (b.centre - p);
        b.momentum = b.mass * (next_centre - b.centre) / dt;
      }
      b.angular_momentum = b.inertia() * mo.angular_velocity * share / dt;
      b.reaction_force = (b.momentum / c_plus - c_minus * b.momentum_before) / dtbar - F;
      b.reaction_moment = (b.angular_momentum / c_plus - c_minus * b.angular_momentum_before) / dtbar - T;
    } else {
      b.momentum = (c_minus * b.momentum_before + dtbar * F) * c_plus;
      b.angular_momentum = (c_minus * b.angular_momentum_before + dtbar * T) * c_plus;
      if (b.guided()) {
        // The rail takes the load across it and every moment: its reaction, which does no work
        // (the piece only moves along the rail and does not turn).
        b.momentum = b.guide * b.guide.dot(b.momentum), b.angular_momentum.setZero();
        b.reaction_force = b.guide * b.guide.dot(F) - F, b.reaction_moment = -T;
      }
    }
    // As the contact sweep sees it: velocity and angular velocity at t^{n+1/2}, centre and inverse
    // inertia at t^n.
    const Mat3 inv_inertia = b.guided() ? Mat3::Zero() : b.inverse_inertia();
    const Vec3d w = inv_inertia * b.angular_momentum;
    for (int d = 0; d < 3; ++d) {
      rows.centre[k][static_cast<std::size_t>(d)] = b.centre[d], rows.V[k][static_cast<std::size_t>(d)] = b.momentum[d] / b.mass;
      rows.w[k][static_cast<std::size_t>(d)] = w[d];
      for (int e = 0; e < 3; ++e) rows.inv_inertia[k][static_cast<std::size_t>(3 * d + e)] = inv_inertia(d, e);
    }
    rows.inv_mass[k] = 1.0 / b.mass;
    rows.moved[k] = 0;
  }
}

void RigidBodies::drift(const Model& model, const double* u, double dt, double* v_half) {
  const RigidRows& rows = *rows_;
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    RigidBody& b = bodies_[k];
    Mat3 next_rotation;
    if (b.prescribed) {
      const Vec3d w = b.angular_velocity_of(b.angular_momentum);
      const double angle = w.norm() * dt;
      next_rotation = (angle > 0 ? Mat3(Eigen::AngleAxisd(angle, w / w.norm())) : Mat3::Identity()) * b.rotation;
    } else {
      // The contact sweep's impulses, taken back as momentum and angular momentum (untouched
      // bodies keep theirs bit for bit).
      if (rows.moved[k]) {
        b.momentum = b.mass * Vec3d(rows.V[k].data());
        b.angular_momentum = b.inertia() * Vec3d(rows.w[k].data());
      }
      next_rotation = b.guided() ? b.rotation : free_rotation(b, b.rotation, b.angular_momentum, dt);
    }
    next_[k] = {b.centre + dt * b.momentum / b.mass, next_rotation};
    // The nodes' velocities over the step: the secant ones, so u^{n+1} = u^n + dt v^{n+1/2} lands
    // on the body (place() then sets it exactly).
    for (std::size_t j = 0; j < b.nodes.size(); ++j) {
      const auto a = static_cast<std::size_t>(b.nodes[j]);
      const Vec3d x = next_[k].centre + next_[k].rotation * Vec3d(&b.offset[3 * j]);
      for (std::size_t d = 0; d < 3; ++d) v_half[3 * a + d] = (x[static_cast<Eigen::Index>(d)] - model.X[3 * a + d] - u[3 * a + d]) / dt;
    }
  }
}

void RigidBodies::place(const Model& model, double* u) {
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    bodies_[k].centre = next_[k].centre, bodies_[k].rotation = next_[k].rotation;
    rigid_displacements(bodies_[k], model, bodies_[k].centre, bodies_[k].rotation, u);
  }
}

double RigidBodies::kinetic_energy(bool first) const {
  double kinetic = 0;
  for (const RigidBody& b : bodies_)
    kinetic += first ? b.kinetic_energy(b.momentum_before, b.angular_momentum_before)
                     : b.kinetic_energy(0.5 * (b.momentum_before + b.momentum), 0.5 * (b.angular_momentum_before + b.angular_momentum));
  return kinetic;
}

void RigidBodies::add_work(double alpha, double dt_prev, double dt, bool first, double& damp_back, double& damp_fwd, double& ext_back,
                           double& ext_fwd) const {
  for (const RigidBody& b : bodies_) {
    const Vec3d P_n = first ? b.momentum_before : 0.5 * (b.momentum_before + b.momentum);
    const Vec3d L_n = first ? b.angular_momentum_before : 0.5 * (b.angular_momentum_before + b.angular_momentum);
    const Vec3d V_old = b.momentum_before / b.mass, V_new = b.momentum / b.mass;
    const Vec3d w_old = b.angular_velocity_of(b.angular_momentum_before), w_new = b.angular_velocity_of(b.angular_momentum);
    damp_back += alpha * dt_prev * (P_n.dot(V_old) + L_n.dot(w_old));
    damp_fwd += alpha * dt * (P_n.dot(V_new) + L_n.dot(w_new));
    ext_back += dt_prev * (b.reaction_force.dot(V_old) + b.reaction_moment.dot(w_old));
    ext_fwd += dt * (b.reaction_force.dot(V_new) + b.reaction_moment.dot(w_new));
  }
}

}  // namespace tactus::solver
