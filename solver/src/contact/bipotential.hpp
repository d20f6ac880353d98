#pragma once
// The bi-potential solve over constraint rows (paper eqs. 11-12), independent of how the rows
// were found: compliances, warm start, Uzawa iterations in Gauss-Seidel order, then the status of
// each row, the resultants and the reactions' work.
#include <vector>

#include "tactus/solver/contact.hpp"

namespace tactus::solver {

struct RowSolveInput {
  const std::vector<ContactPair>* pairs;
  const ContactSettings* settings;
  const double* v_old;        // v^{n-1/2}
  const double* inv_mass;     // per dof, 0 on prescribed dofs
  double velocity_per_force;  // dtbar / (1 + alpha dtbar / 2)
  double dt, dt_prev;
  std::vector<PairStepReport>* per_pair = nullptr;  // one per pair, overwritten (or none)
};

// Solves for rows.reaction, correcting v (free half-step velocities) in place; `last` holds the
// previous step's reactions per pair and slave (warm start, updated here).
ContactStepReport solve_rows(ContactRows& rows, double* v, std::vector<std::vector<double>>& last, const RowSolveInput& in);

}  // namespace tactus::solver
