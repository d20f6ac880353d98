#pragma once
// The bi-potential solve over constraint rows (paper eqs. 11-12), independent of how the rows
// were found: compliances, warm start, Uzawa iterations in Gauss-Seidel order, then the status of
// each row, the resultants and the reactions' work.
#include <array>
#include <cstdint>
#include <vector>

#include "tactus/solver/contact.hpp"

namespace tactus::solver {

// Free rigid bodies among the rows' nodes (rigid.hpp): a node's velocity is its body's,
// V + w x (x - c), and a reaction on it moves the whole body (dV = c r / m, dw = c I^-1 (x - c) x r),
// so the rows on one body are coupled through it within the sweep.
struct RigidRows {
  const std::int32_t* body_of_node = nullptr;  // per node: a free rigid body's index, or < 0
  const double* X = nullptr;                   // reference positions and displacements at t^n (3 per node)
  const double* u = nullptr;
  std::vector<Vec3> centre, V, w;                  // per body; V and w (at t^{n+1/2}) are updated by the solve
  std::vector<char> moved;                         // per body: the solve changed V or w
  std::vector<double> inv_mass;                    // per body
  std::vector<std::array<double, 9>> inv_inertia;  // per body, world frame at t^n, row by row (0 on a rail)
  std::vector<Vec3> guide;                         // per body: its rail's unit direction, or 0 (free)
  // An impulse as it moves body b's centre: along its rail only when it has one.
  Vec3 along_rail(int b, const Vec3& f) const {
    const Vec3& g = guide[static_cast<std::size_t>(b)];
    if (g[0] == 0 && g[1] == 0 && g[2] == 0) return f;
    const double s = dot(g, f);
    return {s * g[0], s * g[1], s * g[2]};
  }
  int body(std::int32_t node) const { return body_of_node && body_of_node[node] >= 0 ? body_of_node[node] : -1; }
  Vec3 arm(std::int32_t node, int b) const;       // x_node - c_b
  Vec3 velocity(std::int32_t node, int b) const;  // V_b + w_b x arm
  Vec3 turn(int b, const Vec3& moment) const;     // I_b^-1 moment
};

struct RowSolveInput {
  const std::vector<ContactPair>* pairs;
  const ContactSettings* settings;
  const double* v_old;        // v^{n-1/2}
  const double* inv_mass;     // per dof, 0 on prescribed dofs
  double velocity_per_force;  // dtbar / (1 + alpha dtbar / 2)
  double dt, dt_prev;
  std::vector<PairStepReport>* per_pair = nullptr;  // one per pair, overwritten (or none)
  RigidRows* rigid = nullptr;                       // free rigid bodies (or none)
  const double* X = nullptr;                        // reference positions (3 per node), to cut the sweep in slabs
  int threads = 1;                                  // for the blocked sweep
};

// Solves for rows.reaction, correcting v (free half-step velocities) in place; `last` holds the
// previous step's reactions per pair and slave (warm start, replaced here by this step's).
ContactStepReport solve_rows(ContactRows& rows, double* v, WarmStart& last, const RowSolveInput& in);

}  // namespace tactus::solver
