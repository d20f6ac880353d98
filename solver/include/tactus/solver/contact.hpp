#pragma once
// Frictional contact by the bi-potential method (paper §2.1, eqs. 1-12).
//
// A contact pair is a slave side (nodes of a surface, with tributary areas) and a master kind
// (ContactMaster: a deformable surface, a rigid plane; rigid bodies, mortar segments and
// self-contact fit the same seam). Each step, every master kind turns the slave nodes near it
// into constraint rows (ContactRows): the degrees of freedom a reaction acts on with their
// weights (slave +1 and master -N_i today; mortar D and -M; a rigid body's [I, -(x - x_c)x]), the
// normal and the gap. The bi-potential solver works on rows only, with no closest-point
// assumption, and the integrator talks to contact through one velocity correction,
// ContactSolver::correct_velocities.
//
// Conventions (docs/design.md): n is the master's outward normal, the gap h = (x_s - x_m) . n
// (negative = penetration); the reaction r acts on the slave node and -r on the master side with
// the row's weights; r = r_t + r_n n with Signorini h >= 0, r_n >= 0, h r_n = 0 (eq. 5) and the
// Coulomb cone K_mu = {|r_t| <= mu r_n} (eq. 7). Per step the reactions are found from the free
// (contact-less) half-step velocities by the bi-potential fixed point r = proj(tau, K_mu) with
// the augmented traction tau = r + rho(-u_t - (u_n + mu |u_t|) n) (eqs. 11-12), where u is the
// relative velocity and its normal part includes h/dt so that no penetration is left after the
// position update. The rows are coupled through shared nodes and solved by Uzawa iterations in
// Gauss-Seidel order (each correction applied to the velocities at once).
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "tactus/solver/contact_settings.hpp"

namespace tactus {
class StateArchive;
}

namespace tactus::solver {

struct Model;
struct DetectionScratch;  // contact/detection.hpp: per-step search storage, reused
struct RigidRows;         // contact/bipotential.hpp: free rigid bodies among the rows' nodes
class ContactMaster;

// Mortar's edge pass (ContactSpec::edge_pass): master edges whose two faces' normals differ by
// more than this are edges (a block's 90 deg; not a faceted curved surface's few degrees).
inline constexpr double kEdgePassAngleDeg = 30;

// One directed contact pair: the slave nodes of a surface against a master kind.
struct ContactPair {
  std::string name;  // "contact[0] hand/skin -> block/surface", for messages and output
  double friction = 0;
  std::vector<std::int32_t> slave_nodes;      // internal node ids, unique, ascending
  std::vector<double> slave_area;             // tributary area (1/3 of adjacent slave triangles), m^2
  std::vector<std::int32_t> slave_triangles;  // 3 internal node ids each: the slave surface (mortar integrates over it)
  std::shared_ptr<const ContactMaster> master;
  double search_scale = 0;  // length the search distance and tolerances scale with (mean master edge), m
  // How the pair's rows count in the step's resultants, which describe the force on the first
  // slave body of its [[contact]] entry: the second pass of a two_pass entry has its slaves on the
  // other body (sign -1), and both passes see the same interface (the entry's area is the larger
  // of theirs). `entry`: the pairs of one [[contact]] entry share it.
  double report_sign = 1;
  int entry = 0;
  // Self-contact (slave and master the same surface): both sides of a touching fold are slaves, so
  // the pair's area counts half of its pressing nodes' areas, and its force (internal to the
  // body) is not added to the step's resultant.
  bool self_contact = false;
  // Mortar's edge pass (surfaces.cpp): its slaves are the master's edge nodes, and its rows' normal
  // reactions are reported as pressure on the slave surface's nodes they act on (each node's
  // share over its tributary area in the entry's mortar pass), so that surface's pressure field
  // carries the edge's load too.
  bool edge_pass = false;
};

// One directed pair's share of a step: force on its slave nodes, normal force, contact area
// (tributary area of the nodes pressing), peak pressure, pressing nodes.
struct PairStepReport {
  Vec3 force{0, 0, 0};
  double normal_force = 0, area = 0, peak_pressure = 0;
  std::size_t active = 0;
};

enum class ContactStatus : std::uint8_t { open = 0, stick = 1, slip = 2 };

// The constraint rows of one step (one per slave node near a master), structure of arrays. Row k
// acts on dofs nodes[start[k] .. start[k+1]) with weights: the slave node first (+1), then the
// master side.
struct ContactRows {
  std::vector<std::int32_t> pair, slave_index;  // the pair, and the slave's position in its slave_nodes
  std::vector<std::int32_t> start{0};
  std::vector<std::int32_t> nodes;
  std::vector<double> weights;
  std::vector<double> normal;  // 3 per row
  std::vector<double> gap;     // h at t^n
  std::vector<double> area;    // slave tributary area
  // The solve's results:
  std::vector<double> reaction;    // 3 per row, N (force at t^n)
  std::vector<double> compliance;  // w
  std::vector<ContactStatus> status;
  // Scratch of the solve, kept so that no step allocates: each row's change in the last sweep,
  // and the rows swept alone when the sweep creeps (contact/bipotential.cpp).
  std::vector<double> change;
  std::vector<std::size_t> creeping;
  // The blocked sweep's (contact/bipotential.cpp): the rows of block b are
  // block_rows[block_start[b] .. block_start[b + 1]), then those between blocks; per node its
  // block while they are cut (-1 after); per block its largest change and reaction in a sweep.
  std::vector<std::int32_t> block_start, block_rows, between_blocks, node_block, row_block;
  std::vector<double> block_change;
  // The rows the slabs were last cut for (their starts and nodes), the slabs asked for and made.
  std::vector<std::int32_t> cut_start, cut_nodes;
  int cut_asked = 0, cut_blocks = 1;
  // When each node's velocity last changed and each row was last updated, in the sweep's order,
  // and whether that update changed nothing: such a row whose nodes did not move since is skipped.
  std::vector<std::int64_t> node_time, row_time;
  std::vector<char> quiet;

  void clear();
  std::size_t size() const { return pair.size(); }
  std::int32_t slave(std::size_t k) const { return nodes[static_cast<std::size_t>(start[k])]; }
  // Appends a row: the slave node, the master nodes with their weights, normal, gap, area.
  void add(std::int32_t pair_index, std::int32_t slave_index, std::int32_t slave_node, const std::int32_t* master_nodes, const double* master_weights,
           int masters, const Vec3& n, double h, double a);
};

// A master kind: turns the slave nodes of a pair near it into constraint rows (one virtual call
// per pair and step, never per node).
class ContactMaster {
 public:
  virtual ~ContactMaster() = default;
  virtual std::string describe() const = 0;  // "rigid plane", "deformable surface (412 triangles)"
  // Its triangles (3 internal node ids each, outward), empty for a rigid plane.
  virtual const std::vector<std::int32_t>& triangles() const = 0;
  // Rows for the slave nodes of `pair` (index pair_index) within `band` of this master, at the
  // current positions x (3 per node).
  virtual void detect(const ContactPair& pair, std::int32_t pair_index, const double* x, double band, DetectionScratch& scratch, ContactRows& rows,
                      int threads) const = 0;
};

// Master kinds.
std::shared_ptr<const ContactMaster> rigid_plane_master(const Vec3& point, const Vec3& outward_normal);
// `triangles`: 3 internal node ids each, ordered so that (b - a) x (c - a) points out of the master body.
// self_contact: the pair's slave surface is this same surface (skin on skin): a slave node's own
// neighbourhood (the triangles touching it or its ring) is never its master, and a triangle is its
// master only when the two face each other.
std::shared_ptr<const ContactMaster> deformable_surface_master(std::vector<std::int32_t> triangles, bool self_contact = false);
// The same surface as a mortar (segment-to-segment) master (contact/mortar.cpp): each slave node's
// row carries the master nodes its tributary surface overlaps, weighted by the mortar integrals.
std::shared_ptr<const ContactMaster> mortar_surface_master(std::vector<std::int32_t> triangles);

// Building pairs from surfaces of the model (internal numbering).
// Fills slave_nodes and slave_area from the slave triangles; without a search scale yet, their
// mean edge becomes it.
void set_slave_surface(ContactPair& pair, const Model& model, const std::vector<std::array<int, 3>>& triangles);
// Orients every triangle outward from the tets of `model` that own it and makes it the pair's
// deformable master; its mean edge becomes the search scale. InputError naming `where` when a
// triangle is not a face of any tet.
void set_master_surface(ContactPair& pair, const Model& model, const std::vector<std::array<int, 3>>& triangles, const std::string& where,
                        bool mortar = false);
// The slave surface of `pair` against itself (self-contact, node to surface): slave nodes and
// areas as set_slave_surface, master as deformable_surface_master(..., true).
void set_self_contact_surface(ContactPair& pair, const Model& model, const std::vector<std::array<int, 3>>& triangles, const std::string& where);
void set_rigid_plane(ContactPair& pair, const Vec3& point, const Vec3& outward_normal);
// The triangles (internal node ids), each ordered so that (b - a) x (c - a) points out of the tet
// it bounds; owners[t]: how many tets have triangle t as a face (0: none, it is kept as given;
// 2: the triangle is inside the body). Contact surfaces and pressure loads are oriented by it.
std::vector<std::int32_t> outward_triangles(const Model& model, const std::vector<std::array<int, 3>>& triangles, std::vector<int>& owners);
// The triangles of physical surface `tag` of body `body` (default the first) of the model's
// input mesh, in internal numbering.
std::vector<std::array<int, 3>> surface_triangles(const Model& model, std::size_t body, int tag);
std::vector<std::array<int, 3>> surface_triangles(const Model& model, int tag);
// The contact entries as directed pairs on model.contact_pairs, each made by its method
// (contact_method, chosen once per entry): node to surface (two per two_pass entry; a rigid plane;
// self-contact) or mortar (with its edge pass). Bodies and surface groups are named as in
// model.bodies; errors name "contact[k]" in model.source.
void add_contacts(Model& model, const std::vector<ContactSpec>& contacts);

// The closed-form projection on the Coulomb cone K_mu in the frame of n (docs/design.md, eq. 12):
// r = tau inside the cone; 0 in the polar cone (mu |tau_t| <= -tau_n); otherwise onto its surface
// r_n = (tau_n + mu |tau_t|) / (1 + mu^2), r_t = mu r_n tau_t / |tau_t|.
Vec3 coulomb_cone_projection(const Vec3& tau, const Vec3& n, double mu);

// One node with scalar compliance w (velocity change per unit reaction) and free relative velocity
// u_free (normal part already including h/dt): the bi-potential iterations with rho = 1/w, to the
// relative tolerance given. The reference for the local solver tests.
struct LocalContactResult {
  Vec3 reaction{0, 0, 0};
  int iterations = 0;
};
LocalContactResult bipotential_local_solve(const Vec3& u_free, const Vec3& n, double w, double mu, double tolerance = 1e-14,
                                           int max_iterations = 1000);

// What one step of contact did, for the history and the energy balance.
struct ContactStepReport {
  std::size_t candidates = 0, active = 0, sticking = 0, slipping = 0;
  int iterations = 0;
  bool converged = true;
  double residual = 0;            // last max |dr| / max |r|
  Vec3 force{0, 0, 0};            // force on the slave bodies (sum of r, the second passes' reversed), N
  double normal_force = 0;        // sum of r_n over every pass, N
  double area = 0;                // tributary area of nodes with r_n > 0 (per two-pass entry the larger pass's), m^2
  double peak_pressure = 0;       // Pa, the largest windowed nodal pressure (ContactSolver::set_pressure_window)
  std::int32_t peak_node = -1;    // internal node of the peak pressure
  double peak_step_pressure = 0;  // Pa, the largest r_n / A of this step alone (first-touch impulses grow like 1/dt)
  // normal_force and area averaged over the pressure's window (set_pressure_window), N and m^2:
  // one step's values carry the first-touch impulses, these converge as dt -> 0.
  double windowed_normal_force = 0, windowed_area = 0;
  // Rows found deeper inside than recovery_speed x dt, pushed out at recovery_speed; the deepest's gap (m, < 0) and slave node.
  std::size_t recovering = 0;
  double deepest_gap = 0;
  std::int32_t deepest_node = -1;
  // The sweep's blocks (1: one sweep in row order) and the rows swept in order: those between the
  // blocks, swept after them, or every row when there is one block.
  int sweep_blocks = 1;
  std::size_t rows_in_order = 0;
  // Work of the reactions over du^{n-1/2} and du^{n+1/2} (trapezoid halves), relative motion:
  double normal_work_back = 0, normal_work_forward = 0, friction_work_back = 0, friction_work_forward = 0;
  // Work of the supports that take the reaction shares landing on prescribed dofs (halves).
  double support_work_back = 0, support_work_forward = 0;
};

// Reactions of the previous step per pair and slave node (3 each): the Uzawa iterations start from
// them (projected on the new cone), so a lasting contact converges in one or two sweeps. `written`
// lists the (pair, slave index) entries the last step set, so that the next clears them in
// O(rows) instead of O(surface) (a self-contact pair's slaves are the whole skin).
struct WarmStart {
  std::vector<std::vector<double>> reaction;
  std::vector<std::int32_t> written;  // pair, slave index, ...
  void find_written();                // from the non-zero entries (a checkpoint read back)
};

// The largest pressure averaged over a disc of `sensor_area` (a pressure sensor's cell) centred
// at one of `centres`: the mean of the nodal pressure, interpolated over the surface's triangles
// (3 model nodes each) at x = X + u, inside the disc.
struct AveragedPressure {
  double value = 0;
  std::int32_t node = -1;
  Vec3 at{0, 0, 0};  // the centre node's current position
};
AveragedPressure disc_averaged_peak(const double* X, const double* u, const std::vector<std::int32_t>& surface, const double* nodal_pressure,
                                    const std::vector<std::int32_t>& centres, double sensor_area);

// The integrator's view of contact: one velocity correction per step.
class ContactSolver {
 public:
  explicit ContactSolver(const Model& model);  // pairs and settings from the model
  ~ContactSolver();
  bool empty() const { return pairs_.empty(); }
  // Every node the contact sweep reads or moves: the pairs' slave nodes and master vertices, ascending.
  const std::vector<std::int32_t>& contact_nodes() const { return contact_nodes_; }
  void set_threads(int threads) { threads_ = threads; }  // detection runs in parallel over slave nodes
  int threads() const { return threads_; }

  // Throws InputError when, at displacement u, a slave node lies deeper than 1e-3 of the search
  // scale inside a master (used at t = 0).
  void check_initial_overlap(const double* u) const;

  // One contact step. v (in/out): free half-step velocities v^{n+1/2}, corrected in place.
  // v_old: v^{n-1/2}. velocity_per_force: dv = velocity_per_force * inv_mass * r (dtbar / (1 + alpha dtbar/2)).
  // dt: the position step that follows; dt_prev: the one before (for the work halves).
  // rigid: free rigid bodies among the nodes (their velocities read and changed as bodies).
  ContactStepReport correct_velocities(const double* u, double* v, const double* v_old, const double* inv_mass, double velocity_per_force, double dt,
                                       double dt_prev, RigidRows* rigid = nullptr);
  // The next correct_velocities' detection, done ahead at the displacement u it will be called
  // with (the integrator runs it during the stress pass at that u, on one thread while the others
  // compute forces): correct_velocities then takes these rows instead of searching.
  void detect_ahead(const double* u);

  const ContactRows& rows() const { return rows_; }
  const std::vector<ContactPair>& pairs() const { return pairs_; }
  // The last step's share of each directed pair (pairs() order).
  const std::vector<PairStepReport>& pair_reports() const { return pair_reports_; }
  // The reported pressure of a node is r_n / A averaged over an exponential window of time constant
  // tau: p <- p + w (r_n / A - p), w = min(1, dtbar / tau), so a first-touch impulse I shows as
  // about I / tau whatever the step (r_n / A of one step is I / dtbar). 0: no averaging.
  void set_pressure_window(double tau) { pressure_window_ = tau; }
  double pressure_window() const { return pressure_window_; }
  // Node-to-surface searches so far (pair-steps) and how many of them rebuilt the Verlet lists.
  struct SearchCounts {
    std::size_t searches = 0, builds = 0;
  };
  SearchCounts search_counts() const;

  // Point fields in the internal numbering: pressure (r_n / area), traction (r_t / area, 3),
  // status (0 open, 1 stick, 2 slip; -1 not near a master surface), gap (NaN when not near),
  // area (the tributary area the pressure is over: the largest of the node's rows; 0 without one).
  struct NodeFields {
    std::vector<double> pressure, traction, status, gap, area;
  };
  void node_fields(NodeFields& f) const;

  // The reported pressure field, interpolated linearly on the slave triangles at displacement u,
  // averaged over the part of the slave surfaces within the radius of a disc of `sensor_area`
  // around each pressed node: the largest average and its centre node (internal); value 0 when
  // nothing presses. A node's own value grows as the mesh is refined under an edge load; this
  // average converges.
  using AveragedPressure = tactus::solver::AveragedPressure;
  AveragedPressure averaged_peak_pressure(const double* u, double sensor_area) const;

  // Saves or restores what the next step reads: the warm-start reactions, the windowed pressures,
  // each pair's search state (Verlet lists, grid, mortar rows and where they were built) and the
  // rows detected ahead for the next step.
  void checkpoint(StateArchive& archive);
  // Loading: every restored index (triangles, nodes, slaves, list starts) within this model's.
  void validate_restored(const StateArchive& archive) const;

 private:
  void detect(const double* u, double search_factor, ContactRows& rows);

  const Model& model_;
  std::vector<ContactPair> pairs_;
  ContactSettings settings_;
  ContactRows rows_;
  ContactRows ahead_rows_;  // detect_ahead's rows, for the next step (valid while ahead_)
  bool ahead_ = false;
  std::vector<double> x_;                    // current positions, filled per step at contact_nodes_ only
  bool x_known_ = false;                     // x_ holds the last search's positions (not yet: a fresh solver)
  std::vector<std::int32_t> contact_nodes_;  // every pair's slave nodes and master vertices, once
  WarmStart last_reaction_;
  std::vector<PairStepReport> pair_reports_;
  double pressure_window_ = 0;
  std::vector<double> step_pressure_, windowed_pressure_;  // per node (slave nodes only used)
  // The slave nodes whose step_pressure_ this step set, and those whose windowed pressure is not 0
  // (ascending; flagged in is_pressed_): the windows are updated there only, not over the whole skin.
  std::vector<std::int32_t> step_nodes_, pressed_;
  std::vector<char> is_pressed_;
  void find_pressed();                   // from the non-zero windowed pressures (a checkpoint read back)
  std::vector<double> edge_share_area_;  // per node: its mortar-pass tributary area where an edge pass acts
  double windowed_normal_force_ = 0, windowed_area_ = 0;
  std::vector<std::int32_t> slave_union_;  // every pair's slave nodes, once
  // The step's nodal pressures, normal force and area into their exponential windows (pressure_window_).
  void update_windows(ContactStepReport& report, double dtbar);
  int threads_ = 1;
  std::vector<DetectionScratch> scratch_;  // one per pair (grids and Verlet lists)
};

}  // namespace tactus::solver
