// linear_elastic: St Venant-Kirchhoff ("linear elastic" in the paper's sense: S linear in E in
// the total-Lagrangian frame), S = lambda tr(E) I + 2 mu E, W = lambda/2 tr(E)^2 + mu E:E; bone
// (paper §3.2: E = 10 GPa, nu = 0.22) and the block.
#include "law.hpp"

namespace tactus::solver {
namespace {

struct LinearElastic {
  static constexpr const char* kName = "linear_elastic";
  double youngs = 0, poisson = 0, density = 0;
  double lambda = 0, mu = 0;

  static SectionSpec parameters() {
    return {"",
            "St Venant-Kirchhoff (linear S(E) in the total-Lagrangian frame); bone, the block.",
            {number("E", "Pa", "Young's modulus", 0, true), number("nu", "", "Poisson's ratio", -1, true, 0.5, true),
             number("density", "kg/m^3", "mass density in the reference configuration", 0, true)}};
  }
  static LinearElastic create(const MaterialValues& v, const std::string&, std::vector<double>&) {
    LinearElastic m{parameter(v, "E"), parameter(v, "nu"), parameter(v, "density")};
    m.mu = m.youngs / (2.0 * (1.0 + m.poisson));
    m.lambda = m.youngs * m.poisson / ((1.0 + m.poisson) * (1.0 - 2.0 * m.poisson));
    return m;
  }
  double small_strain_bulk() const { return lambda + 2.0 * mu / 3.0; }
  double small_strain_shear() const { return mu; }

  TACTUS_KERNEL_INLINE StressPoint evaluate(const Mat3& F, const Mat3& /*cof*/, double /*J*/, const double* /*data*/) const {
    const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
    const double trE = E.trace();
    const Mat3 S = lambda * trE * Mat3::Identity() + 2.0 * mu * E;
    StressPoint s;
    s.P = F * S;
    s.W = 0.5 * lambda * trE * trE + mu * E.squaredNorm();
    s.modulus = lambda + 2.0 * mu;
    return s;
  }
};

}  // namespace
}  // namespace tactus::solver

TACTUS_MATERIAL(LinearElastic)
