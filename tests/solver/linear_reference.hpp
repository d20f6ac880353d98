#pragma once
// Independent small-strain references for the dynamics tests: the dense stiffness K = sum_e
// V_e B_e^T D B_e of an isotropic linear-elastic tet mesh (assembled here from the standard B
// matrix, not through the solver's kernels), and the generalized eigenproblem K phi = w^2 M phi
// with the solver's lumped mass.
#include <Eigen/Dense>
#include <vector>

#include "tactus/core/stable_step.hpp"
#include "tactus/solver/model.hpp"

namespace tactus::testkit {

inline Eigen::MatrixXd linear_stiffness(const solver::Model& m, double E, double nu) {
  const Eigen::Index n = static_cast<Eigen::Index>(3 * m.num_nodes);
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n, n);
  const double lam = E * nu / ((1 + nu) * (1 - 2 * nu)), mu = E / (2 * (1 + nu));
  Eigen::Matrix<double, 6, 6> D = Eigen::Matrix<double, 6, 6>::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) D(i, j) = lam;
    D(i, i) += 2 * mu;
    D(3 + i, 3 + i) = mu;  // engineering shear strains
  }
  for (std::size_t e = 0; e < m.num_elements; ++e) {
    Vec3 x[4];
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 3; ++c) x[a][c] = m.X[3 * static_cast<std::size_t>(m.conn[4 * e + a]) + c];
    const TetGradients g = tet_shape_gradients(x[0], x[1], x[2], x[3]);
    Eigen::Matrix<double, 6, 12> B = Eigen::Matrix<double, 6, 12>::Zero();
    for (int a = 0; a < 4; ++a) {
      const double gx = g.grad[a][0], gy = g.grad[a][1], gz = g.grad[a][2];
      B(0, 3 * a) = gx, B(1, 3 * a + 1) = gy, B(2, 3 * a + 2) = gz;
      B(3, 3 * a + 1) = gz, B(3, 3 * a + 2) = gy;  // yz
      B(4, 3 * a) = gz, B(4, 3 * a + 2) = gx;      // xz
      B(5, 3 * a) = gy, B(5, 3 * a + 1) = gx;      // xy
    }
    const Eigen::Matrix<double, 12, 12> Ke = g.volume * B.transpose() * D * B;
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) K.block<3, 3>(3 * m.conn[4 * e + a], 3 * m.conn[4 * e + b]) += Ke.block<3, 3>(3 * a, 3 * b);
  }
  return K;
}

struct Modes {
  Eigen::VectorXd omega2;  // ascending
  Eigen::MatrixXd shapes;  // columns, full dof vectors (zero on constrained dofs)
};

// K phi = w^2 M phi on the free dofs, via the symmetric form M^{-1/2} K M^{-1/2}.
inline Modes generalized_modes(const solver::Model& m, const Eigen::MatrixXd& K) {
  std::vector<Eigen::Index> free;
  for (std::size_t i = 0; i < 3 * m.num_nodes; ++i)
    if (!m.constrained[i]) free.push_back(static_cast<Eigen::Index>(i));
  const Eigen::Index nf = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd A(nf, nf);
  Eigen::VectorXd s(nf);
  for (Eigen::Index i = 0; i < nf; ++i) s[i] = 1.0 / std::sqrt(m.mass[static_cast<std::size_t>(free[i]) / 3]);
  for (Eigen::Index i = 0; i < nf; ++i)
    for (Eigen::Index j = 0; j < nf; ++j) A(i, j) = s[i] * K(free[i], free[j]) * s[j];
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(A);
  Modes out;
  out.omega2 = es.eigenvalues();
  out.shapes = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(3 * m.num_nodes), nf);
  for (Eigen::Index k = 0; k < nf; ++k)
    for (Eigen::Index i = 0; i < nf; ++i) out.shapes(free[i], k) = s[i] * es.eigenvectors()(i, k);
  return out;
}

}  // namespace tactus::testkit
