#include "tactus/core/stable_step.hpp"

#include <cmath>
#include <limits>

namespace tactus {

TetGradients tet_shape_gradients(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3) {
  // Columns of Dm are the edges from x0; grad N_{1..3} are the rows of Dm^{-1}, grad N_0 = -sum.
  const double a[3] = {x1[0] - x0[0], x1[1] - x0[1], x1[2] - x0[2]};
  const double b[3] = {x2[0] - x0[0], x2[1] - x0[1], x2[2] - x0[2]};
  const double c[3] = {x3[0] - x0[0], x3[1] - x0[1], x3[2] - x0[2]};
  // Rows of Dm^{-1} = cross products / det.
  const double bxc[3] = {b[1] * c[2] - b[2] * c[1], b[2] * c[0] - b[0] * c[2], b[0] * c[1] - b[1] * c[0]};
  const double cxa[3] = {c[1] * a[2] - c[2] * a[1], c[2] * a[0] - c[0] * a[2], c[0] * a[1] - c[1] * a[0]};
  const double axb[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  const double det = a[0] * bxc[0] + a[1] * bxc[1] + a[2] * bxc[2];
  TetGradients g;
  g.volume = det / 6.0;
  if (det == 0) return g;
  for (int k = 0; k < 3; ++k) {
    g.grad[1][k] = bxc[k] / det;
    g.grad[2][k] = cxa[k] / det;
    g.grad[3][k] = axb[k] / det;
    g.grad[0][k] = -(g.grad[1][k] + g.grad[2][k] + g.grad[3][k]);
  }
  return g;
}

double characteristic_length(const TetGradients& g) {
  double s = 0;
  for (const auto& v : g.grad) s += v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
  return s > 0 && g.volume != 0 ? 1.0 / std::sqrt(s) : 0.0;
}

double characteristic_length(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3) {
  return characteristic_length(tet_shape_gradients(x0, x1, x2, x3));
}

double dilatational_wave_speed(double bulk_modulus, double shear_modulus, double density) {
  return std::sqrt((bulk_modulus + 4.0 * shear_modulus / 3.0) / density);
}

CriticalStep critical_time_step(const TetMesh& mesh, const std::function<double(int)>& wave_speed) {
  CriticalStep best;
  best.dt = std::numeric_limits<double>::infinity();
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    const double c = wave_speed(mesh.tet_group[e]);
    if (!(c > 0)) continue;
    const auto& t = mesh.tets[e];
    const double L = characteristic_length(mesh.nodes[t[0]], mesh.nodes[t[1]], mesh.nodes[t[2]], mesh.nodes[t[3]]);
    if (L / c < best.dt) best = {L / c, static_cast<int>(e), mesh.tet_group[e], L};
  }
  return best;
}

}  // namespace tactus
