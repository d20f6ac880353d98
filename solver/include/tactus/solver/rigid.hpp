#pragma once
// Rigid bodies (material type "rigid", materials/rigid.cpp): each connected piece of a body's
// rigid tets is one rigid body with six degrees of freedom. Its mass, centre and inertia tensor
// come from its tets (exact for linear tets of uniform density) plus the lumped masses that the
// deformable tets around it put on the nodes they share with it; those nodes, and every node of
// its tets, move with it: x_a = c + Q (X_a - c_0).
//
// Time integration, in the integrator's half-step form (explicit.hpp): the momentum P and the
// spatial angular momentum L are kicked by the force and the moment (about c) of everything that
// acts on the body's nodes at t^n - the deformable tets' internal forces on the shared nodes,
// external loads, contact - with the same mass damping as the nodes:
//   P^{n+1/2} = [(1 - alpha dtbar/2) P^{n-1/2} + dtbar F^n] / (1 + alpha dtbar/2), L likewise;
// then c moves by dt P/m and Q by the free rotation under L over dt, split into exact rotations
// about the principal axes, x(dt/2) y(dt/2) z(dt) y(dt/2) x(dt/2) (Dullweber, Leimkuhler &
// McLachlan 1997): symplectic and time-reversible, it conserves L exactly (each sub-rotation
// turns the body and its body-frame angular momentum together) and the energy without drift.
// A body with a prescribed velocity and angular velocity (bodies.rigid_velocity,
// rigid_angular_velocity, scaled by rigid_curve) moves by them; the force and moment that hold it
// are its reaction.
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tactus/solver/energy.hpp"
#include "tactus/solver/material.hpp"
#include "tactus/solver/model.hpp"

namespace tactus {
class StateArchive;
}

namespace tactus::solver {

struct RigidRows;  // contact/bipotential.hpp: the free bodies as the contact sweep sees them

// A prescribed motion of one rigid piece: the point `pivot` (reference coordinates, carried with
// the piece; empty: its centre of mass) moves at `velocity` and the piece turns about it at
// `angular_velocity`, both scaled by curve(t). Over a step the pivot moves by the velocity's
// integral and the piece turns about it by the angular velocity's, exactly.
struct RigidMotion {
  Vec3d velocity = Vec3d::Zero(), angular_velocity = Vec3d::Zero();
  std::optional<Vec3d> pivot;
  std::int32_t curve = -1;
};

struct RigidBody {
  std::string name;                  // "hand/bone #3": the body, the material, the piece
  std::size_t body = 0;              // model.bodies index
  std::vector<std::int32_t> groups;  // the physical volume tags of its tets (file tags of its body), ascending
  std::vector<std::int32_t> nodes;   // internal ids, ascending
  std::vector<double> offset;        // per node, X_a - c_0 (3 each)
  double mass = 0;
  Vec3d centre0 = Vec3d::Zero();    // reference centre of mass
  Mat3 inertia0 = Mat3::Zero();     // about centre0, reference frame
  Mat3 axes = Mat3::Identity();     // principal axes of inertia0 (columns, right-handed)
  Vec3d principal = Vec3d::Zero();  // principal moments
  bool prescribed = false;          // moves as `motion` says (bodies.rigid_velocity, or RigidBodies::prescribe)
  RigidMotion motion;
  // A free piece on a rail (bodies.rigid_guide; [grasp] handle_guided): it translates along this
  // unit direction only and does not turn; the rail takes the rest of the load (its reaction,
  // which does no work). Zero: free in all six degrees of freedom.
  Vec3d guide = Vec3d::Zero();
  bool guided() const { return guide.squaredNorm() > 0; }
  // State: centre and rotation at t^n, momentum and spatial angular momentum at t^{n+1/2} (after
  // advance_velocity; at t^{n-1/2} before it), and the previous half step's.
  Vec3d centre = Vec3d::Zero();
  Mat3 rotation = Mat3::Identity();
  Vec3d momentum = Vec3d::Zero(), angular_momentum = Vec3d::Zero();
  Vec3d momentum_before = Vec3d::Zero(), angular_momentum_before = Vec3d::Zero();
  // The force and moment (about the centre) on it at t^n from everything but its support; for a
  // prescribed body, the support's (the reaction).
  Vec3d force = Vec3d::Zero(), moment = Vec3d::Zero();
  Vec3d reaction_force = Vec3d::Zero(), reaction_moment = Vec3d::Zero();

  // The world inertia tensor at the current rotation, its inverse, and I(t)^-1 L.
  Mat3 inertia() const { return rotation * inertia0 * rotation.transpose(); }
  Mat3 inverse_inertia() const;
  Vec3d angular_velocity_of(const Vec3d& L) const { return inverse_inertia() * L; }
  Vec3d rotation_vector() const;  // the rotation from the reference as angle x axis (rad), for the outputs
  double kinetic_energy(const Vec3d& P, const Vec3d& L) const { return 0.5 * P.squaredNorm() / mass + 0.5 * L.dot(angular_velocity_of(L)); }
};

// Per node, 1 where a tet of a rigid material block holds it (the nodes the rigid bodies move).
std::vector<char> rigid_nodes(const Model& model);

// The rigid bodies of a model, found from its rigid material blocks and its bodies' rigid_* keys,
// at rest in the reference placement. InputError when a [[boundary]] constrains a node of a rigid
// body (give the body's rigid_velocity instead).
std::vector<RigidBody> find_rigid_bodies(const Model& model);

// The free rotation over dt under the spatial angular momentum L (DLM splitting): the new rotation.
Mat3 free_rotation(const RigidBody& body, const Mat3& rotation, const Vec3d& L, double dt);

// Positions of a body's nodes at centre c and rotation Q, as displacements: u_a = c + Q o_a - X_a.
void rigid_displacements(const RigidBody& body, const Model& model, const Vec3d& centre, const Mat3& rotation, double* u);

void checkpoint_rigid_bodies(StateArchive& archive, std::vector<RigidBody>& bodies);

// The rigid pieces of a model through the steps of the integrator (explicit.hpp, eq. 35 in its
// half-step form): a kick of their momenta by the forces at t^n, the contact sweep's impulses, a
// drift to t^{n+1}, and their placement. ExplicitSolver calls these; the pieces' state is here.
class RigidBodies {
 public:
  // Per node: kPrescribed on a prescribed piece, the free piece's index, or -1 (none).
  static constexpr std::int32_t kPrescribed = -2;

  RigidBodies();
  ~RigidBodies();
  RigidBodies(RigidBodies&&) noexcept;
  RigidBodies& operator=(RigidBodies&&) noexcept;

  // Finds the pieces, gives each its initial momenta (the body's initial velocity field at its
  // centre, or its prescribed motion at t = 0) and its nodes that velocity in both half-step
  // arrays; their contact inverse masses become 0 (the piece takes a reaction as a whole).
  void init(const Model& model, double* v_half, double* v_prev_half, double* contact_inv_mass);
  // The seam for joint-driven motion: piece k moves as `motion` says from now on (InputError when
  // a piece has no such index).
  void prescribe(std::size_t piece, const RigidMotion& motion);

  bool empty() const { return bodies_.empty(); }
  const std::vector<RigidBody>& bodies() const { return bodies_; }
  std::vector<RigidBody>& bodies_for_checkpoint() { return bodies_; }
  bool holds(std::size_t node) const { return !piece_of_node_.empty() && piece_of_node_[node] != -1; }
  const std::int32_t* piece_of_node() const { return piece_of_node_.empty() ? nullptr : piece_of_node_.data(); }
  RigidRows* contact_rows() { return rows_.get(); }

  // The force and moment (about its centre) at t^n on each piece's nodes: internal forces f plus
  // external(dof) (RigidBody::force, moment).
  void sum_loads(const Model& model, const double* f, const ExternalForces& external, const double* u);
  // P, L to t^{n+1/2} from those loads, with the mass damping factors c_minus, c_plus; a
  // prescribed piece gets the momenta of its motion over [time, t_next] and the reaction that
  // makes them.
  void kick(const Model& model, const double* u, double time, double t_next, double dt, double dtbar, double c_minus, double c_plus);
  // After the contact sweep: its impulses taken back, the centre and rotation at t^{n+1}, and the
  // nodes' secant velocities over the step in v_half.
  void drift(const Model& model, const double* u, double dt, double* v_half);
  // The pieces at t^{n+1}: exactly on the body, not the sum of secant steps.
  void place(const Model& model, double* u);
  // Kinetic energy at t^n (first step: at t^0).
  double kinetic_energy(bool first) const;
  // Their part of the step's work: mass damping -alpha P, -alpha L and a prescribed piece's
  // support, over the half steps behind (dt_prev) and ahead (dt).
  void add_work(double alpha, double dt_prev, double dt, bool first, double& damp_back, double& damp_fwd, double& ext_back, double& ext_fwd) const;

 private:
  std::vector<RigidBody> bodies_;
  std::vector<std::int32_t> piece_of_node_;
  std::unique_ptr<RigidRows> rows_;  // the free ones, as the contact sweep sees them
  struct Placement {
    Vec3d centre;
    Mat3 rotation;
  };
  std::vector<Placement> next_;  // each piece at t^{n+1} (from drift)
};

}  // namespace tactus::solver
