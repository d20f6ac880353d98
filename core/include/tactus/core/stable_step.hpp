#pragma once
// The explicit stable time step of linear tets, shared by the solver (re-evaluated every stress
// pass) and the mesher's quality report, so both quote the same number.
//
// For a 4-node tet with lumped mass m_a = rho V / 4 and stiffness K_e = V B^T D B, the largest
// element frequency obeys omega^2 <= 4 c^2 sum_a |grad N_a|^2, with c the dilatational speed
// sqrt((K + 4 mu / 3) / rho). Central differences are stable for dt <= 2 / omega, hence
//   dt_e = L_e / c,   L_e = (sum_a |grad N_a|^2)^(-1/2),
// a bound that never exceeds the element's true limit (the smallest height can overestimate it
// by up to 2x on flat slivers). The global step is safety * min_e dt_e.
#include <array>
#include <functional>

#include "tactus/core/mesh.hpp"

namespace tactus {

struct TetGradients {
  std::array<Vec3, 4> grad;  // grad N_a in the reference configuration
  double volume = 0;         // signed; <= 0 means an inverted or degenerate tet
};

TetGradients tet_shape_gradients(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3);

// L_e = (sum_a |grad N_a|^2)^(-1/2); 0 for a degenerate tet.
double characteristic_length(const TetGradients& g);
double characteristic_length(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3);

// sqrt((K + 4 mu / 3) / rho): the P-wave speed of an isotropic solid.
double dilatational_wave_speed(double bulk_modulus, double shear_modulus, double density);

struct CriticalStep {
  double dt = 0;      // min_e L_e / c_e (no safety factor applied)
  int element = -1;   // the limiting tet
  int group = 0;      // its physical volume tag
  double length = 0;  // its L_e
};

// min over tets of L_e / c(group); groups for which wave_speed returns <= 0 are skipped.
CriticalStep critical_time_step(const TetMesh& mesh, const std::function<double(int group)>& wave_speed);

}  // namespace tactus
