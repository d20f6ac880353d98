#pragma once
// Frictional contact by the bi-potential method (paper §2.1, eqs. 1-12), node to surface.
//
// Conventions (docs/design.md): for a slave node s and its closest master point m on a triangle with
// outward normal n, the gap is h = (x_s - x_m) . n (negative = penetration); the reaction r acts
// on the slave node and -r is shared over the triangle's nodes with the barycentric weights N_i;
// r = r_t + r_n n with Signorini h >= 0, r_n >= 0, h r_n = 0 (eq. 5) and the Coulomb cone
// K_mu = {|r_t| <= mu r_n} (eq. 7). Per step the reactions are found from the free (contact-less)
// half-step velocities by the bi-potential fixed point r = proj(tau, K_mu) with the augmented
// traction tau = r + rho(-u_t - (u_n + mu |u_t|) n) (eqs. 11-12), where u is the relative velocity
// and its normal part includes h/dt so that no penetration is left after the position update.
// The local problems are coupled through shared master nodes and solved by Uzawa iterations in
// Gauss-Seidel order (each correction is applied to the velocities at once).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "tactus/solver/scenario.hpp"

namespace tactus::solver {

struct Model;

// One directed contact pair: slave nodes against master triangles (or a rigid plane).
struct ContactPair {
  std::string name;  // "contact[0] hand/skin -> block/surface", for messages and output
  double friction = 0;
  std::vector<std::int32_t> slave_nodes;  // internal node ids, unique
  std::vector<double> slave_area;         // tributary area (1/3 of adjacent slave triangles), m^2
  // Master triangles, 3 internal node ids each, ordered so that (b - a) x (c - a) points out of
  // the master body.
  std::vector<std::int32_t> master_triangles;
  bool rigid_plane = false;
  std::array<double, 3> plane_point{0, 0, 0}, plane_normal{0, 0, 1};  // normal out of the rigid half-space
  double master_edge = 0;  // mean master edge length (search distance and tolerances), m
};

// Contact with a rigid plane for slave triangles given in internal numbering (tests, benchmarks).
// `master_triangles` empty and rigid_plane true, or triangles oriented as described above.
// Fills slave_nodes and slave_area from the slave triangles.
void set_slave_surface(ContactPair& pair, const Model& model, const std::vector<std::array<int, 3>>& triangles);
// Orients every triangle outward from the tets of `model` that own it and records it as master.
// Throws InputError naming `where` when a triangle is not a face of any tet.
void set_master_surface(ContactPair& pair, const Model& model, const std::vector<std::array<int, 3>>& triangles,
                        const std::string& where);
// The triangles of physical surface `tag` of the model's input mesh, in internal numbering.
std::vector<std::array<int, 3>> surface_triangles(const Model& model, int tag);
// The scenario's [[contact]] entries as directed pairs (two per two_pass entry) on model.contact_pairs.
void add_scenario_contacts(Model& model, const Scenario& scenario);

// The closed-form projection on the Coulomb cone K_mu in the frame of n (docs/design.md, eq. 12):
// r = tau inside the cone; 0 in the polar cone (mu |tau_t| <= -tau_n); otherwise onto its surface
// r_n = (tau_n + mu |tau_t|) / (1 + mu^2), r_t = mu r_n tau_t / |tau_t|.
std::array<double, 3> coulomb_cone_projection(const std::array<double, 3>& tau, const std::array<double, 3>& n, double mu);

// One node with scalar compliance w (velocity change per unit reaction) and free relative velocity
// u_free (normal part already including h/dt): the bi-potential iterations with rho = 1/w, to the
// relative tolerance given. The reference for the local solver tests.
struct LocalContactResult {
  std::array<double, 3> reaction{0, 0, 0};
  int iterations = 0;
};
LocalContactResult bipotential_local_solve(const std::array<double, 3>& u_free, const std::array<double, 3>& n, double w,
                                           double mu, double tolerance = 1e-14, int max_iterations = 1000);

enum class ContactStatus : std::uint8_t { open = 0, stick = 1, slip = 2 };

// The candidates of the last solve (one per slave node near a master surface), structure of arrays.
struct ContactState {
  std::vector<std::int32_t> pair, slave, triangle;  // triangle -1 for a rigid plane
  std::vector<std::int32_t> slave_index;             // position of the slave in its pair's slave_nodes
  std::vector<double> weights;                       // 3 per candidate: N_i
  std::vector<double> normal;                        // 3 per candidate
  std::vector<double> gap;                           // h at t^n
  std::vector<double> reaction;                      // 3 per candidate, N (force at t^n)
  std::vector<double> compliance;                    // w
  std::vector<double> area;                          // slave tributary area
  std::vector<ContactStatus> status;
  void clear();
  std::size_t size() const { return slave.size(); }
};

// What one step of contact did, for the history and the energy balance.
struct ContactStepReport {
  std::size_t candidates = 0, active = 0, sticking = 0, slipping = 0;
  int iterations = 0;
  bool converged = true;
  double residual = 0;                 // last max |dr| / max |r|
  std::array<double, 3> force{0, 0, 0};  // sum of r over slave nodes, N
  double normal_force = 0;              // sum of r_n, N
  double area = 0;                      // tributary area of nodes with r_n > 0, m^2
  double peak_pressure = 0;             // Pa
  std::int32_t peak_node = -1;          // internal node of the peak pressure
  // Work of the reactions over du^{n-1/2} and du^{n+1/2} (trapezoid halves), relative motion:
  double normal_work_back = 0, normal_work_forward = 0, friction_work_back = 0, friction_work_forward = 0;
  // Work of the supports that take the reaction shares landing on prescribed dofs (halves).
  double support_work_back = 0, support_work_forward = 0;
};

class ContactSolver {
 public:
  explicit ContactSolver(const Model& model);  // pairs and settings from the model
  bool empty() const { return pairs_.empty(); }
  void set_threads(int threads) { threads_ = threads; }  // detection runs in parallel over slave nodes

  // Detects candidates at the current positions x = X + u; throws InputError when a slave node
  // lies deeper than `overlap_tolerance` inside a master surface (used at t = 0).
  void check_initial_overlap(const double* u) const;

  // One contact step. v (in/out): free half-step velocities v^{n+1/2}, corrected in place.
  // v_old: v^{n-1/2}. velocity_per_force: dv = velocity_per_force * inv_mass * r (dtbar / (1 + alpha dtbar/2)).
  // dt: the position step that follows; dt_prev: the one before (for the work halves).
  ContactStepReport solve(const double* u, double* v, const double* v_old, const double* inv_mass,
                          double velocity_per_force, double dt, double dt_prev);

  const ContactState& state() const { return state_; }
  const std::vector<ContactPair>& pairs() const { return pairs_; }

  // Point fields in the internal numbering: pressure (r_n / area), traction (r_t / area, 3),
  // status (0 open, 1 stick, 2 slip; -1 not near a master surface), gap (NaN when not near).
  void node_fields(std::vector<double>& pressure, std::vector<double>& traction, std::vector<double>& status,
                   std::vector<double>& gap) const;

 private:
  void detect(const double* u);
  void build_grid(const ContactPair& p, const double* x, double margin);

  const Model& model_;
  std::vector<ContactPair> pairs_;
  ContactSettings settings_;
  ContactState state_;
  std::vector<double> x_;  // current positions of all nodes (filled per step)
  // Reactions of the previous step per pair and slave (3 each): the Uzawa iterations start from
  // them (projected on the new cone), so a lasting contact converges in one or two sweeps.
  std::vector<std::vector<double>> last_reaction_;
  int threads_ = 1;
  // Per slave node of the pair being detected: closest triangle (-1 none), weights, normal, gap.
  std::vector<std::int32_t> slot_triangle_;
  std::vector<double> slot_data_;  // 7 per slave: N (3), n (3), h
  // Uniform grid over one pair's master triangles (rebuilt per pair and step; storage reused).
  struct Grid {
    double lo[3]{}, cell = 1;
    int n[3]{1, 1, 1};
    std::vector<std::int32_t> start, items;
    std::vector<std::int32_t> count;
    std::vector<std::array<int, 6>> box;  // cell range of each triangle
    std::vector<double> normal;            // 4 per triangle: unit outward normal, 1 / (2 area); 0 if degenerate
  } grid_;
};

}  // namespace tactus::solver
